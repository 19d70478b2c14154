#!/usr/bin/python3
"""tools/train_cnn/label_mirror_consistency.py on synthetic labels whose mirror images are known exactly."""
import os, sys, unittest

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "train_cnn"))
from label_mirror_consistency import RELIABILITY_SHAPES, partner, rotation  # noqa: E402
import label_mirror_consistency as mc  # noqa: E402

SHAPES = sorted(set(RELIABILITY_SHAPES) | {partner(s) for s in RELIABILITY_SHAPES})


def axis_angle(R):
    theta = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    if theta < 1e-12:
        return np.zeros(3)
    return theta / (2 * np.sin(theta)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def row(omega, weights, euler):
    r = {"key": "", "split": "test", "pitch_deg": euler[0], "yaw_deg": euler[1], "roll_deg": euler[2]}
    r.update({"omega_" + c: v for c, v in zip("xyz", omega)})
    r.update({f"id{k}": 0.0 for k in range(21)})
    r.update(weights)
    return {k: str(v) for k, v in r.items()}


class Consistency(unittest.TestCase):
    def labels(self, extra_deg):
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

    def test_exact_mirror_images_agree(self):
        original, mirrored = self.labels(0.0)
        c = mc.consistency(original, mirrored, list(original))
        self.assertLess(c["rotation"].max(), 1e-3)
        self.assertLess(c["euler"].max(), 1e-9)
        self.assertLess(c["weights"].max(), 1e-12)
        for name, r in c["r"].items():
            self.assertAlmostEqual(r, 1.0, places=9, msg=name)

    def test_a_turned_mirror_image_differs_by_the_turn(self):
        original, mirrored = self.labels(4.0)
        c = mc.consistency(original, mirrored, list(original))
        np.testing.assert_allclose(c["rotation"], 4.0, atol=1e-3)


if __name__ == "__main__":
    unittest.main()
