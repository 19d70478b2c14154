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


class Gains(unittest.TestCase):
    def test_the_factor_that_brings_readings_above_their_rest_level_to_the_labels(self):
        labels = torch.linspace(0, 1, 101).unsqueeze(1)
        estimate = 0.1 + 0.45 * labels                                # rest 0.1, half the size above it
        mask = torch.ones_like(labels)
        gains = train_stage.gains(estimate, labels, mask, {"mouthPucker": 0.1}, ["mouthPucker"])
        self.assertAlmostEqual(gains["mouthPucker"], 2.0, places=4)   # (w - 0.1) / 0.9 = labels / 2

    def test_a_gain_is_clamped_and_1_where_few_frames_show_the_shape(self):
        labels = torch.linspace(0, 1, 101).unsqueeze(1)
        mask = torch.ones_like(labels)
        tiny = train_stage.gains(0.01 * labels, labels, mask, {"x": 0.0}, ["x"])
        self.assertEqual(tiny["x"], train_stage.MAX_GAIN)
        rare = torch.zeros(101, 1)
        rare[:5] = 1.0                                                # five frames show it: too few to tell
        self.assertEqual(train_stage.gains(0.5 * rare, rare, mask, {"x": 0.0}, ["x"])["x"], 1.0)
        self.assertEqual(train_stage.gains(2.0 * labels, labels, mask, {"x": 0.0}, ["x"])["x"], 1.0)  # never below 1

    def test_unlabelled_samples_count_for_neither_gain_nor_agreement(self):
        labels = torch.linspace(0, 1, 101).unsqueeze(1)
        estimate = 0.5 * labels
        mask = torch.ones_like(labels)
        estimate[::2] = 1.0 - labels[::2]                             # nonsense where there is no label
        mask[::2] = 0.0
        self.assertAlmostEqual(train_stage.gains(estimate, labels, mask, {"x": 0.0}, ["x"])["x"], 2.0, places=4)
        self.assertAlmostEqual(train_stage.masked_agreement(estimate, labels, mask, ["x"])["x"], 1.0, places=5)


class Names(unittest.TestCase):
    def test_face_model_names_and_their_mirrors(self):
        self.assertEqual(train_stage.arkit_name("browDown_L"), "browDownLeft")
        self.assertEqual(train_stage.arkit_name("jawOpen"), "jawOpen")
        self.assertEqual(train_stage.mirror_name("mouthSmileLeft"), "mouthSmileRight")
        self.assertEqual(train_stage.mirror_name("browDown_R"), "browDown_L")


if __name__ == "__main__":
    unittest.main()
