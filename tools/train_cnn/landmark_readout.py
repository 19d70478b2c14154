#!/usr/bin/python3
"""A linear readout of expressions from the 68 landmarks, against the landmark fit (docs/expressions.md,
"Session 24"). Tried, not shipped: it measures whether the points carry more of the teacher's expressions
than the fit reads from them.

The readout: the 68 points aligned by a similarity onto the training faces' mean shape, in outer-eye-corner
distances, minus that mean: 136 features; ridge regression (lambda n |W|^2) onto the dense teacher labels
(MediaPipe's mesh fitted with the face model: another model's predictions, not ground truth), trained on
the 300-W training faces' annotated points, each face also mirrored with its labels' sides swapped. The
validation and test splits and every clip stay out, so every clip figure is held out.

Both are measured on the clips tracked by the shipped tracker (`facetrack track CLIP --raw --out
DIR/NAME.jsonl`): the readout on the raw landmarks, the fit by its raw blendshapes, each against the
clip labels (pooled Pearson r) and on the hand-labelled segments (neutral mean, each label's response).

  mkdir -p build/readout/clips build/readout/validation && for c in ../shared/data/clips/*.mp4; do
      build/tools/facetrack track $c --raw --out build/readout/clips/$(basename $c .mp4).jsonl; done
  awk -F, '$2=="validation" {print $1}' build/dense_labels/faces300w.csv | while read k; do
      ln -sf $PWD/../shared/data/faces300w/$k build/readout/validation/${k//\//__}; done
  build/tools/facetrack track build/readout/validation --raw --out build/readout/validation.jsonl
  /usr/bin/python3 tools/train_cnn/landmark_readout.py --tracks build/readout/clips --validation build/readout/validation

With --validation, also the held-out 300-W validation faces (a folder of links named by the label's key,
'/' as '__', tracked as unrelated photos): r, and the contrast between the top tenth of each label and its
lower half.
"""
import argparse, csv, glob, json, os, sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "train_refine"))
from train_refine import MIRROR, mean_shape, similarity  # noqa: E402
from label_mirror_consistency import partner  # noqa: E402

SHAPES = ["browDown_L", "browDown_R", "browInnerUp_L", "browInnerUp_R", "browOuterUp_L", "browOuterUp_R",
          "mouthPucker", "mouthFunnel", "mouthFrown_L", "mouthFrown_R", "jawOpen", "mouthSmile_L", "mouthSmile_R"]


def arkit_name(native):
    """The ARKit name the tracker reports a native shape under (browInnerUp is one ARKit shape)."""
    if native.startswith("browInnerUp"):
        return "browInnerUp"
    return native[:-2] + {"_L": "Left", "_R": "Right"}[native[-2:]] if native[-2:] in ("_L", "_R") else native


def aligned(points, mean):
    """points (68 x 2) by the least-squares similarity onto mean (centred), scaled to unit eye-corner distance."""
    A, t = similarity(points, mean)
    q = points @ A.T + t
    return q / np.linalg.norm(q[36] - q[45])


def reference(shapes):
    """The training shapes' Procrustes mean, centred, at unit eye-corner distance."""
    mean = mean_shape(shapes, 1.0)
    mean -= mean.mean(0)
    return mean / np.linalg.norm(mean[36] - mean[45])


def features(points, mean):
    return (aligned(points, mean) - mean).ravel()


def mirrored(x, mean):
    q = x.reshape(-1, 68, 2) + mean
    q = q[:, MIRROR].copy()
    q[:, :, 0] *= -1
    return (q - mean).reshape(len(x), -1)


def train(x, y, mean, lam):
    swap = [SHAPES.index(partner(s)) for s in SHAPES]
    x = np.vstack([x, mirrored(x, mean)])
    y = np.vstack([y, y[:, swap]])
    mx, my = x.mean(0), y.mean(0)
    xc = x - mx
    w = np.linalg.solve(xc.T @ xc + lam * len(x) * np.eye(x.shape[1]), xc.T @ (y - my))
    return lambda z: np.clip((z - mx) @ w + my, 0.0, 1.0)


def training_faces(points_csv, labels):
    shapes, targets = [], []
    for row in csv.reader(open(points_csv)):
        if row[1] != "annotation":
            continue
        key = row[0].split("faces300w/")[1]
        if key in labels and labels[key]["split"] == "train":
            shapes.append(np.array(row[2:], float).reshape(68, 2))
            targets.append([float(labels[key][s]) for s in SHAPES])
    return shapes, np.array(targets)


def validation_faces(folder, labels, mean, readout):
    x, f, y = [], [], []
    names = sorted(os.listdir(folder))
    for name, line in zip(names, open(folder.rstrip("/") + ".jsonl")):
        d = json.loads(line)
        key = name.replace("__", "/")
        if d["tracked"] and key in labels:
            x.append(features(np.array(d["raw"]["landmarks"]), mean))
            f.append([d["raw"]["blendshapes"][arkit_name(s)] for s in SHAPES])
            y.append([float(labels[key][s]) for s in SHAPES])
    ours, fit, truth = readout(np.array(x)), np.array(f), np.array(y)
    print(f"\n300-W validation, {len(x)} of {len(names)} faces followed: r readout / fit; "
          "contrast (top tenth of the label minus its lower half) readout / fit / label")
    for i, s in enumerate(SHAPES):
        top, low = truth[:, i] >= np.quantile(truth[:, i], 0.9), truth[:, i] <= np.quantile(truth[:, i], 0.5)
        r = [np.corrcoef(v[:, i], truth[:, i])[0, 1] if v[:, i].std() > 0 else float("nan") for v in (ours, fit)]
        c = [v[top, i].mean() - v[low, i].mean() for v in (ours, fit, truth)]
        print(f"{s:15s} r {r[0]:5.2f} / {r[1]:5.2f}   contrast {c[0]:5.2f} / {c[1]:5.2f} / {c[2]:5.2f}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tracks", required=True, help="a folder of `facetrack track --raw` JSONL files, one per clip")
    p.add_argument("--dense", default="build/dense_labels", help="label_dense's output (faces300w.csv, clips.csv)")
    p.add_argument("--points", default="build/refine/points_train.csv", help="eval-landmarks --points-out of the train split")
    p.add_argument("--segments", default="data/expression_labels.csv")
    p.add_argument("--validation", help="a folder of the validation crops, tracked into FOLDER.jsonl (above)")
    p.add_argument("--ridge", type=float, default=1e-4)
    a = p.parse_args()

    faces = {r["key"]: r for r in csv.DictReader(open(os.path.join(a.dense, "faces300w.csv")))}
    frames = {r["key"]: r for r in csv.DictReader(open(os.path.join(a.dense, "clips.csv")))}
    shapes, targets = training_faces(a.points, faces)
    mean = reference(shapes)
    readout = train(np.array([features(s, mean) for s in shapes]), targets, mean, a.ridge)
    print(f"readout trained on {len(shapes)} 300-W training faces (and their mirror images), ridge {a.ridge:g}")

    if a.validation:
        validation_faces(a.validation, faces, mean, readout)

    ours, fit, label, index = {}, {}, {}, {}
    for path in sorted(glob.glob(os.path.join(a.tracks, "*.jsonl"))):
        clip = os.path.basename(path)[:-len(".jsonl")] + ".mp4"
        x, f, y, n = [], [], [], []
        for line in open(path):
            d = json.loads(line)
            key = f"{clip}#{d['frame']}"
            if not d["tracked"] or key not in frames:
                continue
            x.append(features(np.array(d["raw"]["landmarks"]), mean))
            f.append([d["raw"]["blendshapes"][arkit_name(s)] for s in SHAPES])
            y.append([float(frames[key][s]) for s in SHAPES])
            n.append(d["frame"])
        if x:
            ours[clip], fit[clip], label[clip], index[clip] = readout(np.array(x)), np.array(f), np.array(y), np.array(n)
    if not ours:
        raise SystemExit(f"no tracked frame of {a.tracks} has a dense label")

    def pooled(src):
        return np.vstack([src[c] for c in ours])

    truth = pooled(label)
    print(f"\nPearson r against the clip labels, {len(truth)} frames of {len(ours)} clips")
    print(f"{'shape':15s} readout  fit")
    for i, s in enumerate(SHAPES):
        r = [np.corrcoef(pooled(src)[:, i], truth[:, i])[0, 1] if pooled(src)[:, i].std() > 0 else float("nan")
             for src in (ours, fit)]
        print(f"{s:15s} {r[0]:7.2f} {r[1]:5.2f}")

    segments = [row for row in csv.reader(l for l in open(a.segments) if not l.startswith("#"))][1:]

    def segment_mean(src, name):
        rows = [src[c][(index[c] >= int(lo)) & (index[c] <= int(hi))] for c, lo, hi, n in segments if n == name and c in src]
        return np.vstack(rows).mean(0)

    print("\nlabelled segments: neutral mean, then each label's response (its mean minus neutral's): readout / fit / teacher")
    neutral = {k: segment_mean(src, "neutral") for k, src in (("ours", ours), ("fit", fit), ("label", label))}
    for name in ["neutral", "smile", "open_mouth", "funnel", "brows_up", "frown"]:
        print(f"  {name}")
        m = {k: segment_mean(src, name) - (0 if name == "neutral" else neutral[k])
             for k, src in (("ours", ours), ("fit", fit), ("label", label))}
        print("    " + "  ".join(f"{s} {m['ours'][i]:+.2f}/{m['fit'][i]:+.2f}/{m['label'][i]:+.2f}" for i, s in enumerate(SHAPES)))


if __name__ == "__main__":
    main()
