#!/usr/bin/python3
"""tools/experiments/fit_corrections.py's rule on figures whose answer is known."""
import unittest

from tools.experiments import fit_corrections


class Rule(unittest.TestCase):
    def test_a_shape_is_corrected_where_it_agrees_better_and_reads_no_higher_at_rest(self):
        table = {  # ((r, rest, response) of the fit, the same corrected)
            "jawOpen": ((0.5, 0.04, 0.1), (0.6, 0.04, 0.1)),       # better, as low at rest: corrected
            "mouthFunnel": ((0.3, 0.10, 0.0), (0.5, 0.12, 0.0)),   # better, but higher at rest
            "mouthClose": ((0.3, 0.03, 0.0), (0.2, 0.02, 0.0)),    # lower at rest, but agrees less
        }
        self.assertEqual(fit_corrections.chosen(table), ["jawOpen"])

    def test_a_mirror_pair_is_judged_on_its_means_so_both_sides_go_together(self):
        table = {
            "mouthSmile_L": ((0.80, 0.20, 0.6), (0.90, 0.15, 0.6)),
            "mouthSmile_R": ((0.90, 0.10, 0.6), (0.85, 0.12, 0.6)),  # alone it would not be corrected
            "mouthLeft": ((0.20, 0.058, 0.0), (0.50, 0.059, 0.0)),
            "mouthRight": ((0.20, 0.062, 0.0), (0.50, 0.0605, 0.0)),  # the pair's rest 0.0600 -> 0.05975
        }
        self.assertEqual(fit_corrections.chosen(table), ["mouthSmile_L", "mouthSmile_R", "mouthLeft", "mouthRight"])
        table["mouthRight"] = ((0.20, 0.062, 0.0), (0.50, 0.0615, 0.0))  # now 0.0600 -> 0.06025: neither
        self.assertEqual(fit_corrections.chosen(table), ["mouthSmile_L", "mouthSmile_R"])


if __name__ == "__main__":
    unittest.main()
