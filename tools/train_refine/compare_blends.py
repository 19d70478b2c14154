#!/usr/bin/python3
"""Refiner variants measured on the validation split (issue 17, docs/cnn.md "Session 20").

    /usr/bin/python3 tools/train_refine/compare_blends.py build/refine/NET [build/refine/NET2 ...] [--second-round] [--flip]

Each NET is a train_refine.py output (NET.best.pt). Prints each net alone, then LBF blended with all the
nets, the weights per face region chosen on a grid (train_refine.region_shares generalised to several
nets). --second-round: the first net run again on a patch realigned on its own blend; --flip: the first
net averaged with its mirrored patch. Inputs as train_refine.py's (build/refine/faces.npz, points_*.csv).
"""
import argparse, itertools, os, sys

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import train_refine as T  # noqa: E402

# Checkpoints without an "arch" entry are session 19's net.
SESSION19 = {"widths": (16, 32, 32, 64, 64, 128, 128), "strides": (2, 2, 1, 2, 1, 2, 1), "hidden": 256}


def faces_aligned_on(faces, points, mean):
    """`faces` with the patch aligned on `points` in place of LBF's."""
    out = T.Faces.__new__(T.Faces)
    out.keys, out.images, out.truth, out.lbf = faces.keys, faces.images, faces.truth, faces.lbf
    sims = [T.similarity(mean, p) for p in points]
    out.A, out.t = np.stack([s[0] for s in sims]), np.stack([s[1] for s in sims])
    return out


def blend(preds, base, truth):
    """Per region, the weights (one per prediction, sum <= 1, the rest `base`) with the lowest mean error."""
    grid = np.linspace(0, 1, 21)
    out = base.copy()
    for _, a, b in T.REGIONS:
        best = min((T.point_errors(sum(w * p for w, p in zip(ws, preds)) + (1 - sum(ws)) * base, truth)[:, a:b].mean(), ws)
                   for ws in itertools.product(grid, repeat=len(preds)) if sum(ws) <= 1)[1]
        out[:, a:b] = sum(w * p[:, a:b] for w, p in zip(best, preds)) + (1 - sum(best)) * base[:, a:b]
    return out


def main():
    p = argparse.ArgumentParser()
    p.add_argument("nets", nargs="+")
    p.add_argument("--data", default="build/refine")
    p.add_argument("--second-round", action="store_true")
    p.add_argument("--flip", action="store_true")
    a = p.parse_args()
    torch.set_num_threads(2)
    data = np.load(os.path.join(a.data, "faces.npz"))
    names = list(data["names"])
    points = T.read_points(os.path.join(a.data, "points_validation.csv"), names)
    preds, first = [], None
    for path in a.nets:
        saved = torch.load(path + ".best.pt")
        net = T.Refiner(96, **saved.get("arch", SESSION19))
        net.load_state_dict(saved["net"])
        mean = saved["mean"]
        val = T.Faces(data["images"], points, mean, points.keys())
        preds.append(T.predict(net, val, mean, 96, False))
        print(T.report(f"{path} alone", T.point_errors(preds[-1], val.truth)))
        first = first or (net, mean, val)
    print(T.report("LBF", T.point_errors(val.lbf, val.truth)))
    print(T.report("blend of LBF and " + ", ".join(a.nets), T.point_errors(blend(preds, val.lbf, val.truth), val.truth)))
    net, mean, val = first
    if a.second_round:
        round1 = blend(preds[:1], val.lbf, val.truth)
        again = T.predict(net, faces_aligned_on(val, round1, mean), mean, 96, False)
        print(T.report("second round, blended with LBF", T.point_errors(blend([again], val.lbf, val.truth), val.truth)))
    if a.flip:
        flipped = T.predict(net, val, mean, 96, True)
        print(T.report("with the mirrored patch, alone", T.point_errors(flipped, val.truth)))
        print(T.report("with the mirrored patch, blended with LBF", T.point_errors(blend([flipped], val.lbf, val.truth), val.truth)))


if __name__ == "__main__":
    main()
