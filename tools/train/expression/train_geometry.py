#!/usr/bin/python3
"""Trains the expression stage's geometry net (docs/cnn.md): from the 68 landmarks as the pipeline
tracks them and the head's pitch and yaw, the face model's expressions as MediaPipe Face
Landmarker's blendshapes read them (../shared/data/teacher: another model's predictions, not ground
truth; class Teacher of train_stage.py, each shape above its rest level).

  /usr/bin/python3 -m tools.train.expression.train_geometry --tracked build/tracked --net build/cnn/v2 \\
        [--tracked-crops build/tracked_300w] [--lips build/cnn/lips.npz] [--out build/cnn/geometry] [--epochs 60]

--tracked: a folder of `facetrack track CLIP --raw --profile none --out DIR/<clip name>.jsonl`, one
per clip of ../shared/data/clips; --tracked-crops: the 300-W crops as tools/data/track_faces300w.sh
tracks them. The training people's clips and the training crops train it (each face and its mirror
image); the validation people's (data/clip_splits.csv) and the validation crops choose the epoch
and the rest levels, the validation people's the shapes pack_cnn reads from it; the held-out
people's clips are never read. --net: the texture net it is packed beside (NET.columns.txt: the expressions, in order).

Writes OUT.geometry.txt (the net, input standardisation folded into its first layer: pack_cnn
--geometry reads it), OUT.validation_geometry_r.txt and OUT.validation_geometry_rest.txt (per
expression: Pearson r and the rest level on the validation people, read mirror-averaged as the
stage reads them).

The features (expression/geometry_net.hpp computes the same): the 68 points centred on their mean,
rotated so that the line between the eyes' centres (means of points 36-41 and 42-47) is level,
scaled to unit root-mean-square distance from the centre, as x0, y0, x1, ...; then sin(pitch) and
sin(yaw) of the fit's head pose; with --lips, the 40 lip points of train_lips.py in the same frame.
"""
import argparse, csv, json, os

import numpy as np
import torch

from tools.train import nets
from tools.train.expression.train_stage import REST_QUANTILE, Teacher, mirror_name
from tools.train.refine.train_refine import MIRROR

HIDDEN = 256


def read_splits(path="data/clip_splits.csv"):
    with open(path) as f:
        return {r["clip"]: r["split"] for r in csv.DictReader(line for line in f if not line.startswith("#"))}


def normalising_frame(points):
    """Per face of points (N, 68, 2): the centre c (N, 2), the rotation R(-theta) (N, 2, 2) that levels the line
    between the eyes' centres, and the root-mean-square distance s (N,) of the levelled points from c."""
    c = points.mean(1)
    d = points[:, 42:48].mean(1) - points[:, 36:42].mean(1)
    angle = np.arctan2(d[:, 1], d[:, 0])
    cos, sin = np.cos(angle), np.sin(angle)
    unroll = np.stack([np.stack([cos, sin], 1), np.stack([-sin, cos], 1)], 1)
    s = np.sqrt(((points - c[:, None]) ** 2).sum(2).mean(1))
    return c, unroll, s


def normalised(p, c, unroll, s):
    """Points p (N, K, 2) in the frame of normalising_frame: R(-theta) (p - c) / s."""
    return np.einsum("nij,nkj->nki", unroll, p - c[:, None]) / s[:, None, None]


def features(points, pitch_deg, yaw_deg, lips=None):
    """points (N, 68, 2) pixels, pitch and yaw (N,) degrees -> (N, 138); with lips (N, 40, 2), the lip net's
    points already in the normalised frame, (N, 218)."""
    q = normalised(points, *normalising_frame(points))
    parts = [q.reshape(len(points), -1), np.sin(np.radians(pitch_deg))[:, None], np.sin(np.radians(yaw_deg))[:, None]]
    if lips is not None:
        parts.append(lips.reshape(len(points), -1))
    return np.concatenate(parts, 1).astype(np.float32)


def mirrored(points, pitch_deg, yaw_deg, lips=None):
    """The mirror image's points, pose (and lip points): x negated, points renumbered, yaw negated. The
    normalised frame of the mirror image is the mirror of the face's, so normalised lips mirror alike."""
    flipped = points[:, MIRROR].copy()
    flipped[:, :, 0] *= -1
    if lips is None:
        return flipped, pitch_deg, -yaw_deg
    from tools.train.expression.train_lips import LIPS_MIRROR
    flipped_lips = lips[:, LIPS_MIRROR].copy()
    flipped_lips[:, :, 0] *= -1
    return flipped, pitch_deg, -yaw_deg, flipped_lips


def with_lips(sets, lips, which):
    """The sets (part, targets, keys) with each sample's lip points (train_lips.py's OUT.npz) added to its
    part: the teacher's for training, where it has them, else the lip net's; samples without them dropped."""
    index = {k: i for i, k in enumerate(lips[which + "_keys"])}
    net, teacher = lips[which + "_net"], lips[which + "_teacher"]
    out = []
    for part, targets, keys in sets:
        rows = np.array([index.get(k, -1) for k in keys])
        keep = rows >= 0
        points = np.where(np.isnan(teacher[rows]), net[rows], teacher[rows]) if which == "train" else net[rows]
        out.append((tuple(x[keep] for x in part) + (points[keep].astype(np.float32),), targets[keep], [k for k, m in zip(keys, keep) if m]))
    return out


def tracked_lines(path):
    """(line number, record, its 68 points (68 x 2)) of each line of a `facetrack track --raw` file
    with raw landmarks and a pose."""
    with open(path) as f:
        for i, line in enumerate(f):
            r = json.loads(line)
            raw = r.get("raw")
            if r["tracked"] and raw and raw.get("landmarks") is not None and raw.get("pose") is not None:
                yield i, r, np.array(raw["landmarks"], np.float64)


def read_tracked(path, key_of, teacher, names):
    """The tracked lines of a `facetrack track --raw` file that the teacher read: ((points, pitch,
    yaw), targets, keys), or None; key_of(line number, record) is the teacher's key of a line."""
    points, pitch, yaw, targets, keys = [], [], [], [], []
    for i, r, p in tracked_lines(path):
        key = key_of(i, r)
        t = teacher.targets(key, names)
        if t is None:
            continue
        points.append(p); pitch.append(r["raw"]["pose"]["euler_deg"][0]); yaw.append(r["raw"]["pose"]["euler_deg"][1])
        targets.append(t); keys.append(key)
    if not points:
        return None
    return (np.array(points, np.float32), np.array(pitch, np.float32), np.array(yaw, np.float32)), np.array(targets, np.float32), keys


def load_clips(folder, splits, which, teacher, names):
    """Per clip of split `which`, ((points, pitch, yaw), targets, keys) of its tracked frames."""
    out = []
    for file in sorted(os.listdir(folder)):
        clip = file[:-len(".jsonl")] + ".mp4"
        if file.endswith(".jsonl") and splits.get(clip, "train") == which:
            out.append(read_tracked(os.path.join(folder, file), lambda i, r: f"{clip}#{r['frame']}", teacher, names))
    return [o for o in out if o is not None]


def load_crops(folder, which, teacher, names):
    """The 300-W crops of split `which` as tools/data/track_faces300w.sh tracked them."""
    with open(os.path.join(folder, which + ".txt")) as f:
        keys = f.read().split()
    crops = read_tracked(os.path.join(folder, which + ".jsonl"), lambda i, r: keys[i], teacher, names)
    return [crops] if crops is not None else []


def expression_mirror(names):
    return [names.index(mirror_name(n)) for n in names]


class GeometryNet(torch.nn.Module):
    def __init__(self, inputs, outputs, mean, std):
        super().__init__()
        self.register_buffer("mean", mean)
        self.register_buffer("std", std)
        self.body = torch.nn.Sequential(torch.nn.Linear(inputs, HIDDEN), torch.nn.ReLU(), torch.nn.Dropout(0.2),
                                        torch.nn.Linear(HIDDEN, HIDDEN), torch.nn.ReLU(), torch.nn.Linear(HIDDEN, outputs))

    def forward(self, x):
        return torch.sigmoid(self.body((x - self.mean) / self.std))


def predict(net, x, x_mirror, order):
    """Mirror-averaged, as the stage reads it: (f(x) + M f(mirror x)) / 2."""
    net.eval()
    with torch.no_grad():
        return (net(x) + net(x_mirror)[:, order]) / 2


def masked_mse(p, y):
    m = ~torch.isnan(y)
    return ((p - torch.nan_to_num(y)) ** 2 * m).sum() / m.sum().clamp_min(1)


def validation_figures(p, y, people, names):
    """Per expression: Pearson r against the labels on the validation people's frames (the first
    `people` samples: as the texture net's, which pack_cnn compares it with), and the rest level
    over every validation sample: the REST_QUANTILE quantile of the reading where the label is below
    0.05, a sided shape pooled with its partner (the reading is mirror-averaged). The validation people were chosen for showing expressions, several hold
    their brows up most of the time, and the teacher reads browOuterUpLeft above 0.05 on all but 5
    of their 505 frames. No gain, unlike the texture net's: the net reads the kind of input the
    teacher reads, and least-squares gains on five people reached the cap of 3 for three lip shapes,
    which then read 0.2 on a relaxed face."""
    out = {}
    for k, n in enumerate(names):
        m = ~np.isnan(y[:people, k])
        a, b = p[:people][m, k], y[:people][m, k]
        if m.sum() < 10 or a.std() < 1e-6 or b.std() < 1e-6:
            out[n] = (float("nan"), 0.0)
            continue
        partner = names.index(mirror_name(n))
        at_rest = np.concatenate([p[y[:, j] < 0.05, j] for j in sorted({k, partner})])
        rest = float(np.quantile(at_rest if len(at_rest) >= 10 else a[b <= np.median(b)], REST_QUANTILE))
        out[n] = (float(np.corrcoef(a, b)[0, 1]), rest)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tracked", required=True, help="the folder of tracked clips (JSON lines, facetrack track --raw)")
    p.add_argument("--tracked-crops", default="", help="also the 300-W crops as tools/data/track_faces300w.sh tracked them "
                   "(DIR/{train,validation}.{txt,jsonl}): the training crops train, the validation crops help choose the epoch "
                   "and the rest levels")
    p.add_argument("--net", required=True, help="the texture net's prefix (NET.columns.txt)")
    p.add_argument("--teacher", default="../shared/data/teacher")
    p.add_argument("--out", default="build/cnn/geometry")
    p.add_argument("--epochs", type=int, default=60)
    p.add_argument("--lips", default="", help="train_lips.py's OUT.npz: the 40 lip points as 80 more features (the teacher's "
                   "for the training samples, the lip net's for the validation ones, as the stage reads them)")
    a = p.parse_args()
    nets.setup_torch(2, seed=1)
    with open(a.net + ".columns.txt") as f:
        names = f.read().split()[6:]
    teacher = Teacher(a.teacher)
    splits = read_splits()
    order = expression_mirror(names)

    def stacked(sets, with_mirror):
        parts, targets = [p for p, _, _ in sets], [t for _, t, _ in sets]
        X = [features(*part) for part in parts]
        Xm = [features(*mirrored(*part)) for part in parts]
        Y = list(targets)
        if with_mirror:  # the mirror images as samples of their own
            X, Xm, Y = X + Xm, Xm + X, Y + [t[:, order] for t in targets]
        return (torch.tensor(np.concatenate(X)), torch.tensor(np.concatenate(Xm)), torch.tensor(np.concatenate(Y)))

    lips = np.load(a.lips) if a.lips else None
    load = (lambda sets, which: with_lips(sets, lips, which)) if a.lips else (lambda sets, which: sets)
    crops = (lambda which: load_crops(a.tracked_crops, which, teacher, names)) if a.tracked_crops else (lambda which: [])
    x_train, _, y_train = stacked(load(load_clips(a.tracked, splits, "train", teacher, names) + crops("train"), "train"), True)
    people = stacked(load(load_clips(a.tracked, splits, "validation", teacher, names), "validation"), False)
    validation_crops = load(crops("validation"), "validation")
    x_val, xm_val, y_val = (torch.cat([people[i], stacked(validation_crops, False)[i]]) for i in range(3)) if validation_crops else people
    print(f"samples: {len(x_train)} training (with their mirror images), {len(people[0])} validation people's frames, "
          f"{len(x_val) - len(people[0])} validation crops", flush=True)
    net = GeometryNet(x_train.shape[1], len(names), x_train.mean(0), x_train.std(0).clamp_min(1e-4))
    opt = torch.optim.AdamW(net.parameters(), lr=1e-3, weight_decay=1e-3)
    best, best_state = float("inf"), None
    for epoch in range(a.epochs):
        net.train()
        perm = torch.randperm(len(x_train))
        for i in range(0, len(perm), 256):
            idx = perm[i:i + 256]
            # feature noise of 5 % of each feature's spread: the landmarks jitter
            x = x_train[idx] + 0.05 * net.std * torch.randn(len(idx), x_train.shape[1])
            loss = masked_mse(net(x), y_train[idx])
            opt.zero_grad(); loss.backward(); opt.step()
        score = masked_mse(predict(net, x_val, xm_val, order), y_val).item()
        if score < best:
            best, best_state = score, {k: v.clone() for k, v in net.state_dict().items()}
        print(f"epoch {epoch + 1} train {loss.item():.5f} validation {score:.5f}", flush=True)
    net.load_state_dict(best_state)
    figures = validation_figures(predict(net, x_val, xm_val, order).numpy(), y_val.numpy(), len(people[0]), names)
    for i, what in enumerate(("r", "rest")):
        with open(f"{a.out}.validation_geometry_{what}.txt", "w") as f:
            for n, values in figures.items():
                f.write(f"{n} {values[i]:.4f}\n")
    # The standardisation folded into the first layer: W' = W / std, b' = b - W' mean.
    layers = [m for m in net.body if isinstance(m, torch.nn.Linear)]
    with torch.no_grad():
        first_w = layers[0].weight / net.std[None, :]
        first_b = layers[0].bias - first_w @ net.mean
    with open(a.out + ".geometry.txt", "w") as f:
        f.write(f"facetrack geometry net 1\nlayers {len(layers)}\n")
        for i, layer in enumerate(layers):
            w, b = (first_w, first_b) if i == 0 else (layer.weight.detach(), layer.bias.detach())
            f.write(f"{w.shape[0]} {w.shape[1]}\n")
            f.write(" ".join(f"{v:.9g}" for v in w.reshape(-1).tolist()) + "\n")
            f.write(" ".join(f"{v:.9g}" for v in b.tolist()) + "\n")
        # a check pack_cnn and the tests repeat: the first validation frame's features and outputs
        f.write(" ".join(f"{v:.9g}" for v in x_val[0].tolist()) + "\n")
        f.write(" ".join(f"{v:.9g}" for v in net.eval()(x_val[:1])[0].tolist()) + "\n")
    print(f"best validation {best:.5f}; wrote {a.out}.geometry.txt, {a.out}.validation_geometry_{{r,rest}}.txt", flush=True)
    print("validation r: " + " ".join(f"{n} {v[0]:.2f}" for n, v in figures.items() if v[0] == v[0]), flush=True)


if __name__ == "__main__":
    main()
