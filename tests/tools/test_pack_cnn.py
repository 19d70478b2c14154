#!/usr/bin/python3
"""tools/train/pack_cnn's per-expression choices from the trainer's validation files, on a fixture net.

    /usr/bin/python3 tests/tools/test_pack_cnn.py PACK_CNN
"""
import os, subprocess, sys, tempfile, unittest

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
PACK_CNN = None
POSE = ["omega_x", "omega_y", "omega_z", "centre_x", "centre_y", "centre_z"]


def pack(folder, expressions, rest, r, *options, gain=None):
    """Packs tests/data/mirror_fixture.onnx (six pose outputs and two expressions) as a net trained on
    `expressions`, with the trainer's files beside it; returns pack_cnn's output."""
    net = os.path.join(folder, "net.onnx")
    with open(os.path.join(REPO, "tests", "data", "mirror_fixture.onnx"), "rb") as f, open(net, "wb") as g:
        g.write(f.read())
    for suffix, lines in ((".columns.txt", POSE + expressions),
                          (".validation_rest.txt", [f"{n} {v}" for n, v in zip(expressions, rest)]),
                          (".validation_r.txt", [f"{n} {v}" for n, v in zip(expressions, r)]),
                          (".validation_gain.txt", [f"{n} {v}" for n, v in zip(expressions, gain or [1.0] * len(expressions))])):
        with open(os.path.join(folder, "net" + suffix), "w") as f:
            f.write("\n".join(lines) + "\n")
    run = subprocess.run([PACK_CNN, "--nets", net, "--expressions-only", "--mirror-average", *options,
                          "--out", os.path.join(folder, "out.ftm")], capture_output=True, text=True)
    if run.returncode != 0:
        raise AssertionError(run.stdout + run.stderr)
    return run.stdout


class MirrorPairs(unittest.TestCase):
    def test_a_pairs_rest_level_is_the_mean_of_both_sides_whatever_the_names_suffix(self):
        for left, right in (("browDown_L", "browDown_R"), ("jawLeft", "jawRight")):
            with tempfile.TemporaryDirectory() as folder:
                out = pack(folder, [left, right], [0.1, 0.3], [0.9, 0.9], "--rest-from-validation")
                self.assertIn(f"neutral {left} 0.200", out)
                self.assertIn(f"neutral {right} 0.200", out)

    def test_both_sides_of_a_pair_are_reported_or_neither(self):
        with tempfile.TemporaryDirectory() as folder:
            out = pack(folder, ["mouthLeft", "mouthRight"], [0, 0], [0.6, 0.3], "--min-validation-r", "0.5")
            self.assertIn("reported:\n", out)  # mean r 0.45: neither
        with tempfile.TemporaryDirectory() as folder:
            out = pack(folder, ["mouthLeft", "mouthRight"], [0, 0], [0.6, 0.45], "--min-validation-r", "0.5")
            self.assertIn("reported: mouthLeft mouthRight\n", out)  # mean 0.525: both


class GainsAndLeftOut(unittest.TestCase):
    def test_a_pairs_gain_is_the_mean_of_both_sides(self):
        with tempfile.TemporaryDirectory() as folder:
            out = pack(folder, ["browDown_L", "browDown_R"], [0.1, 0.1], [0.9, 0.9], "--rest-from-validation",
                       "--gain-from-validation", gain=[1.5, 2.5])
            self.assertIn("gain browDown_L 2.00", out)
            self.assertIn("gain browDown_R 2.00", out)

    def test_a_gain_needs_the_rest_levels(self):
        with tempfile.TemporaryDirectory() as folder:
            with self.assertRaises(AssertionError):
                pack(folder, ["browDown_L", "browDown_R"], [0.1, 0.1], [0.9, 0.9], "--gain-from-validation")

    def test_a_left_out_shape_is_not_reported_whatever_its_r(self):
        with tempfile.TemporaryDirectory() as folder:
            out = pack(folder, ["noseSneer_L", "noseSneer_R"], [0, 0], [0.9, 0.9], "--min-validation-r", "0.1",
                       "--leave-out", "noseSneer_L,noseSneer_R")
            self.assertIn("reported:\n", out)
        with tempfile.TemporaryDirectory() as folder:
            with self.assertRaises(AssertionError):  # a name the nets do not have
                pack(folder, ["noseSneer_L", "noseSneer_R"], [0, 0], [0.9, 0.9], "--min-validation-r", "0.1",
                     "--leave-out", "noseSneer")


if __name__ == "__main__":
    PACK_CNN = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(REPO, "build", "tools", "pack_cnn")
    unittest.main()
