#!/usr/bin/python3
"""tools/train/expression/train_stage.py's validation figures on synthetic estimates whose answers are known."""
import unittest

import torch

from tools.train.expression import train_stage


def updates(labels, starts):
    """The update start -> label, after six pose outputs (train_stage's layout)."""
    return torch.cat([torch.zeros(len(labels), 6), labels - starts], 1)


class RestLevels(unittest.TestCase):
    def test_the_estimates_ninetieth_percentile_over_the_faces_whose_label_is_at_most_the_median(self):
        n = 1001
        labels = torch.linspace(0, 1, n).unsqueeze(1)                # median 0.5: faces 0..500 are "at rest"
        noise = torch.linspace(0, 0.2, n).unsqueeze(1)               # the estimate reads the label plus a rising noise
        starts = torch.zeros(n, 1)
        pred = updates(labels + noise, starts)                       # the net predicts estimate - start
        levels = train_stage.rest_levels(pred, updates(labels, starts), labels, ["browDown_L"])
        at_rest = (labels + noise)[:501, 0]                          # 0 .. 0.6 evenly: its 0.9 quantile is 0.54
        self.assertAlmostEqual(levels["browDown_L"], at_rest.quantile(0.9).item(), places=5)
        self.assertAlmostEqual(levels["browDown_L"], 0.54, places=3)

    def test_estimates_are_clamped_to_the_weights_range_first(self):
        labels = torch.zeros(100, 1)
        starts = torch.zeros(100, 1)
        pred = updates(torch.full((100, 1), -0.3), starts)           # a net reading below 0 reads 0
        levels = train_stage.rest_levels(pred, updates(labels, starts), labels, ["mouthPucker"])
        self.assertEqual(levels["mouthPucker"], 0.0)


if __name__ == "__main__":
    unittest.main()
