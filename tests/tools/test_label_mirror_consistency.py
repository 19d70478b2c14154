#!/usr/bin/python3
"""tools/experiments/label_mirror_consistency.py on synthetic labels whose mirror images are known exactly."""
import unittest

import numpy as np

from tools.experiments import label_mirror_consistency as mc
from tools.experiments.label_mirror_consistency import RELIABILITY_SHAPES, axis_angle, partner, rotation
from tools.experiments.label_pose_noise import angle_deg

SHAPES = sorted(set(RELIABILITY_SHAPES) | {partner(s) for s in RELIABILITY_SHAPES} | {"jawLeft", "jawRight"})


def row(omega, weights, euler):
    r = {"key": "", "split": "test", "pitch_deg": euler[0], "yaw_deg": euler[1], "roll_deg": euler[2]}
    r.update({"omega_" + c: v for c, v in zip("xyz", omega)})
    r.update({f"id{k}": 0.0 for k in range(21)})
    r.update(weights)
    return {k: str(v) for k, v in r.items()}


def mirrored_labels(extra_deg):
    """Random labels, and their mirror images turned by a further extra_deg about the x axis."""
    rng = np.random.default_rng(1)
    M = np.diag([-1.0, 1.0, 1.0])
    extra = rotation(np.radians([extra_deg, 0.0, 0.0]))
    original, mirrored = {}, {}
    for k in range(50):
        R = rotation(rng.normal(0, 0.3, 3))
        w = {s: rng.uniform(0, 1) for s in SHAPES}
        euler = rng.normal(0, 10, 3)
        original[str(k)] = row(axis_angle(R), w, euler)
        mirrored[str(k)] = row(axis_angle(extra @ M @ R @ M), {partner(s): v for s, v in w.items()},
                               [euler[0], -euler[1], -euler[2]])
    return original, mirrored


class Consistency(unittest.TestCase):
    def test_exact_mirror_images_agree(self):
        original, mirrored = mirrored_labels(0.0)
        c = mc.consistency(original, mirrored, list(original))
        self.assertLess(c["rotation"].max(), 1e-3)
        self.assertLess(c["euler"].max(), 1e-9)
        self.assertLess(c["weights"].max(), 1e-12)
        for name, r in c["r"].items():
            self.assertAlmostEqual(r, 1.0, places=9, msg=name)

    def test_a_turned_mirror_image_differs_by_the_turn(self):
        original, mirrored = mirrored_labels(4.0)
        c = mc.consistency(original, mirrored, list(original))
        np.testing.assert_allclose(c["rotation"], 4.0, atol=1e-3)

    def test_partners_are_named_either_way(self):
        self.assertEqual(partner("browDown_L"), "browDown_R")
        self.assertEqual(partner("jawLeft"), "jawRight")
        self.assertEqual(partner("mouthRight"), "mouthLeft")
        self.assertEqual(partner("jawOpen"), "jawOpen")


class MirrorAveraged(unittest.TestCase):
    def test_an_exact_mirror_image_averages_to_the_label_itself(self):
        original, mirrored = mirrored_labels(0.0)
        for k in original:
            averaged = mc.mirror_averaged(original[k], mirrored[k])
            R = rotation(np.array([float(original[k]["omega_" + c]) for c in "xyz"]))
            A = rotation(np.array([float(averaged["omega_" + c]) for c in "xyz"]))
            self.assertLess(angle_deg(A, R), 1e-3)
            for s in SHAPES:
                self.assertAlmostEqual(float(averaged[s]), float(original[k][s]), places=3)

    def test_a_turned_mirror_image_moves_the_average_half_way(self):
        original, mirrored = mirrored_labels(4.0)
        for k in original:
            mirrored[k]["jawLeft"] = str(float(mirrored[k]["jawLeft"]) + 0.2)  # the mirror image reads jawRight 0.2 more
            averaged = mc.mirror_averaged(original[k], mirrored[k])
            R = rotation(np.array([float(original[k]["omega_" + c]) for c in "xyz"]))
            A = rotation(np.array([float(averaged["omega_" + c]) for c in "xyz"]))
            self.assertAlmostEqual(angle_deg(A, R), 2.0, places=3)
            self.assertAlmostEqual(float(averaged["jawRight"]), float(original[k]["jawRight"]) + 0.1, places=3)


if __name__ == "__main__":
    unittest.main()
