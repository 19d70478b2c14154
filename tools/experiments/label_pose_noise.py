#!/usr/bin/python3
"""An upper bound on the dense teacher labels' frame-to-frame pose noise (docs/cnn.md): per clip,
the second difference in time of the label's rotation, the angle between R(t+1) R(t)^T and
R(t) R(t-1)^T over consecutive frames. For white noise of sigma per frame its mean square is
6 sigma^2; real motion only adds, so sqrt(mean / 6) bounds sigma.

  /usr/bin/python3 -m tools.experiments.label_pose_noise [build/dense_labels/clips.csv]
"""
import csv, sys
from collections import defaultdict

import numpy as np


def rotation(w):
    a = np.linalg.norm(w)
    if a < 1e-12:
        return np.eye(3)
    k = w / a
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip((np.trace(a @ b.T) - 1) / 2, -1, 1)))


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "build/dense_labels/clips.csv"
    clips = defaultdict(list)
    for r in csv.DictReader(open(path)):
        clip, frame = r["key"].rsplit("#", 1)
        clips[clip].append((int(frame), rotation(np.array([float(r[k]) for k in ("omega_x", "omega_y", "omega_z")]))))
    every = []
    for clip, frames in sorted(clips.items()):
        frames.sort(key=lambda f: f[0])
        d = [angle_deg(frames[i + 1][1] @ frames[i][1].T, frames[i][1] @ frames[i - 1][1].T)
             for i in range(1, len(frames) - 1) if frames[i + 1][0] - frames[i - 1][0] == 2]
        every += d
        print(f"{clip:48s} {len(frames):5d} frames: sigma <= {np.sqrt(np.mean(np.square(d)) / 6):.2f} deg")
    print(f"all clips: sigma <= {np.sqrt(np.mean(np.square(every)) / 6):.2f} deg")


if __name__ == "__main__":
    main()
