#!/usr/bin/python3
"""A CNN that refines one side's brow and
eye points (11 of the 68) from a small patch aligned by them, after the shipped pipeline (LBF and the landmark
refiner). One net serves both sides: the subject's left side is mirrored into the right side's layout.

    build/tools/facetrack eval-landmarks ../shared/data/faces300w --split S --dlib none --points-out build/region/points_S.csv
        # S = train, validation, test: the annotation and the shipped pipeline's points
    /usr/bin/python3 -m tools.train.refine.train_region --out build/region/net [--minutes 40] [--size 64]
    /usr/bin/python3 -m tools.train.refine.train_region --out build/region/net --evaluate validation|test [--export] [--brows-only]
    build/tools/pack_refiner --base models/landmark_refiner.ftm --sides build/region/net.onnx --out models/landmark_refiner.ftm --provenance "..."

Inputs: build/refine/faces.npz (load_faces.py: every 300-W crop, grey) and the points above. The patch
(SIZE x SIZE) is the crop warped by the similarity that puts the side's 11 pipeline points best onto their mean
shape; the net regresses where the annotated points lie in it (offsets from the mean shape, patch pixels).
Training: the train split's faces, both sides, the alignment perturbed (rotation, scale, shift) and photometric
changes; with --profiled also their copies turned to large yaw (face profiling, docs/cnn.md). The validation split
(and its turned copies) picks the epoch and, for the brows and for the eyes, the net's share of the answer (the rest
the pipeline's), on the sum of each set's error relative to the pipeline's; the test split is read only with
--evaluate test. --export writes the best epoch as
OUT.onnx (opset 13, eval mode, BatchNorm folded: what OpenCV 4.6's dnn loads) and OUT.side.txt (patch size, the
22 mean-shape values, the 11 shares) for pack_refiner --sides.

--expressions CSV (tried, not shipped: docs/decisions.md): the net also reads the side's brow shapes (browDown,
browInnerUp, browOuterUp of that side) from label_dense's faces300w.csv, the dense teacher labels (MediaPipe's mesh
fitted with the face model: another model's predictions, not ground truth); a turned copy carries its crop's labels.
--init starts from a trained net (its point rows kept). The log adds each shape's Pearson r and mean absolute error on
the validation sides, and the epoch is chosen on the points' score plus the readings' error over a constant guess's:

    /usr/bin/python3 -m tools.train.refine.train_region --out build/region/e8 --widths 8,16,32,64 --strides 2,2,2,2 --hidden 128 \
        --profiled build/profiled --minutes 15 --expressions build/dense_labels/faces300w.csv --init build/region/c8.best.pt --lr 5e-4

--region jaw (tried, not shipped: docs/decisions.md): the same for the jaw's sides, points 0-7 and their mirror
images 16-9 (the chin stays the landmark refiner's), with a share each for the outer (0-4) and the lower jaw (5-7); the
patch is 0.7 of its size across the side's taller extent. Not exported: the refine stage runs the brows and eyes' net.
"""
import argparse, csv, math, os, re, time

import numpy as np
import torch
import torch.nn.functional as F

from tools.train.nets import export_onnx, setup_torch, standardise
from tools.train.refine.train_refine import MIRROR, Refiner, photometric, read_points, similarity, warp


PIPELINE = "facetrack LBF + refiner"
# --region: the subject's right side's points (image left), and the parts of them that each take their own share of the
# net's answer. The jaw's sides leave the chin (point 8) to the landmark refiner: both sides would move it.
REGIONS = {
    "brows": (list(range(17, 22)) + list(range(36, 42)), (("brows", slice(0, 5)), ("eyes", slice(5, 11)))),
    "jaw": (list(range(0, 8)), (("outer jaw", slice(0, 5)), ("lower jaw", slice(5, 8)))),
}
RIGHT, PARTS = REGIONS["brows"]
LEFT = [MIRROR[i] for i in RIGHT]  # the same points of the other side, in the same order once mirrored


def use_region(name):
    global RIGHT, PARTS, LEFT
    RIGHT, PARTS = REGIONS[name]
    LEFT = [MIRROR[i] for i in RIGHT]


# --expressions: the side's brow shapes, read from its patch beside its points (dense teacher labels: MediaPipe's mesh
# fitted with the face model, not ground truth). The right side's patch reads the subject's right brow (_R).
EXPRESSIONS = ("browDown", "browInnerUp", "browOuterUp")


class Sides:
    """Every face of a split, both sides: image (mirrored for the left side), annotation, pipeline points and the
    patch -> image similarity from the pipeline's points."""

    def __init__(self, images, points, mean, keys, by_box=False, labels=None, names=None):
        self.keys = sorted(keys)
        crops, truth, init, flipped, norm, expr = [], [], [], [], [], []
        for k in self.keys:
            ann, pipe = points[k]
            # the error's unit: the outer-eye-corner distance (300-W's NME), or for turned copies, whose eye
            # corners close up, sqrt(w h) of the annotation's box (the large-pose NME)
            unit = math.sqrt(np.ptp(ann[:, 0]) * np.ptp(ann[:, 1])) if by_box else np.linalg.norm(ann[36] - ann[45])
            image = torch.from_numpy(images[k]).float()[None] / 255.0
            width = image.shape[-1]
            for side, flip in ((RIGHT, False), (LEFT, True)):
                t, p = ann[side].copy(), pipe[side].copy()
                if flip:
                    t[:, 0], p[:, 0] = width - 1 - t[:, 0], width - 1 - p[:, 0]
                crops.append(image.flip(-1) if flip else image)
                truth.append(t)
                init.append(p)
                flipped.append(flip)
                norm.append(unit)
                label = labels.get(source_key(names[k])) if labels is not None else None
                expr.append(np.full(len(EXPRESSIONS), np.nan) if label is None else label["L" if flip else "R"])
        self.images = torch.stack(crops)
        self.expr = np.stack(expr)
        self.truth, self.init, self.flipped, self.norm = np.stack(truth), np.stack(init), np.array(flipped), np.array(norm)
        self.width = self.images.shape[-1]
        sims = [similarity(mean, p) for p in self.init]
        self.A = np.stack([s[0] for s in sims])
        self.t = np.stack([s[1] for s in sims])

    def join(self, other):
        """These sides and the other's, as one set."""
        self.images = torch.cat([self.images, other.images])
        for name in ("truth", "init", "flipped", "norm", "A", "t", "expr"):
            setattr(self, name, np.concatenate([getattr(self, name), getattr(other, name)]))
        return self


def source_key(name):
    """The 300-W crop a name is, or was profiled from ("afw/1_1@0_yaw+35.pgm" -> "afw/1_1.jpg")."""
    m = re.match(r"(.*)@\d+_yaw[-+]\d+\.pgm$", name)
    return m.group(1) + ".jpg" if m else name


def read_expression_labels(path):
    """{crop key: {"L": 3 values, "R": 3 values}} of EXPRESSIONS from label_dense's faces300w.csv."""
    out = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            out[row["key"]] = {side: np.array([float(row[f"{e}_{side}"]) for e in EXPRESSIONS]) for side in "LR"}
    return out


def side_mean(shapes, size):
    """Procrustes mean of the sides' annotated points, centred in the patch, 0.7 size across (wide or tall)."""
    ref = shapes[0] - shapes[0].mean(0)
    for _ in range(5):
        ref = np.mean([s @ A.T + t for s in shapes for A, t in [similarity(s, ref)]], 0)
        ref -= ref.mean(0)
    ref *= 0.7 * size / max(np.ptp(ref[:, 0]), np.ptp(ref[:, 1]))
    return ref + (size - 1) / 2.0


def batch(sides, idx, mean, size, rng, augment):
    A, t = sides.A[idx].copy(), sides.t[idx].copy()
    n = len(idx)
    if augment:
        centre = np.full(2, (size - 1) / 2.0)
        angle = np.deg2rad(rng.normal(0, 4, n))
        scale = np.exp(rng.normal(0, 0.05, n))
        shift = rng.normal(0, 0.03 * size, (n, 2))
        for i in range(n):
            c, s = math.cos(angle[i]) * scale[i], math.sin(angle[i]) * scale[i]
            P = np.array([[c, -s], [s, c]])
            t[i] = A[i] @ (centre - P @ centre + shift[i]) + t[i]
            A[i] = A[i] @ P
    x = warp(sides.images[idx], torch.from_numpy(A).float(), torch.from_numpy(t).float(), size)
    truth = np.einsum("bij,bnj->bni", np.linalg.inv(A), sides.truth[idx] - t[:, None, :])
    if augment:
        x = photometric(x, rng)
    target = torch.from_numpy((truth - mean[None]).reshape(n, -1)).float()
    return standardise(x), target, A, t, torch.from_numpy(sides.expr[idx]).float()


def predict(net, sides, mean, size):
    """The refined side points in (possibly mirrored) image pixels, N x 11 x 2, and the brow readings,
    N x len(EXPRESSIONS) (no columns for a net without them)."""
    net.eval()
    out, readings = [], []
    with torch.no_grad():
        for start in range(0, len(sides.truth), 256):
            idx = np.arange(start, min(start + 256, len(sides.truth)))
            x, _, A, t, _ = batch(sides, idx, mean, size, None, augment=False)
            y = net(x).numpy()
            u = y[:, :2 * len(RIGHT)].reshape(-1, len(RIGHT), 2) + mean[None]
            out.append(np.einsum("bij,bnj->bni", A, u) + t[:, None, :])
            readings.append(y[:, 2 * len(RIGHT):])
    return np.concatenate(out), np.concatenate(readings)


def errors(points, sides):
    """Per side and point, the error over the face's unit (Sides: the outer-eye-corner distance, or sqrt(w h))."""
    return np.linalg.norm(points - sides.truth, axis=2) / sides.norm[:, None]


def score(sets, refined, share):
    """The validation score: per set (300-W validation, and the turned copies), the blend's mean error over the
    pipeline's, summed (1 per set: no better)."""
    return sum(errors(blended(r, v, share), v).mean() / errors(v.init, v).mean() for v, r in zip(sets, refined))


def shares(sets, refined):
    """The net's share, for each part, with the lowest score (grid 0, 0.05, ..., 1)."""
    grid = np.linspace(0, 1, 21)
    best = {}
    for name, part in PARTS:
        scores = [sum(errors(w * r + (1 - w) * v.init, v)[:, part].mean() / errors(v.init, v)[:, part].mean()
                      for v, r in zip(sets, refined)) for w in grid]
        best[name] = grid[int(np.argmin(scores))]
    return best


def point_shares(share):
    w = np.zeros(len(RIGHT))
    for name, part in PARTS:
        w[part] = share[name]
    return w


def blended(net_points, sides, share):
    w = point_shares(share)
    return w[None, :, None] * net_points + (1 - w[None, :, None]) * sides.init


def summary(name, points, sides):
    e = errors(points, sides)
    return f"{name}: " + ", ".join(f"{part} {100 * e[:, where].mean():.2f} %" for part, where in PARTS)


def expression_summary(name, got, sides):
    """Per brow shape, Pearson r and mean absolute error against the labels (both sides pooled)."""
    parts = []
    for j, e in enumerate(EXPRESSIONS):
        known = ~np.isnan(sides.expr[:, j])
        r = np.corrcoef(got[known, j], sides.expr[known, j])[0, 1]
        parts.append(f"{e} r {r:.2f} mae {np.abs(got[known, j] - sides.expr[known, j]).mean():.3f}")
    return f"{name}: " + ", ".join(parts)


def turn_asymmetry(points):
    """How far a face's 68 points look turned, from the points alone: along the eye line, the nose tip's distance to
    one jaw side's (points 0-3) against the other's (13-16), (r - l) / (r + l); about 0 on a frontal face."""
    eyes = (points[45] - points[36]) / np.linalg.norm(points[45] - points[36])
    r, l = (points[30] - points[0:4].mean(0)) @ eyes, (points[13:17].mean(0) - points[30]) @ eyes
    return (r - l) / (r + l)


def by_turn(name, points, sides, refined, share):
    """The pipeline's and the blend's errors on the side's points by the face's |turn_asymmetry| (the pipeline's points):
    whether the net helps photographed turned faces too, not only face profiling's copies."""
    turn = np.repeat([abs(turn_asymmetry(points[k][1])) for k in sides.keys], 2)  # both sides of each face
    before, after = errors(sides.init, sides).mean(1), errors(blended(refined, sides, share), sides).mean(1)
    for lo, hi in ((0, 0.1), (0.1, 0.2), (0.2, 0.3), (0.3, 0.5), (0.5, 2.0)):
        m = (turn >= lo) & (turn < hi)
        if m.any():
            print(f"{name} |asymmetry| {lo}-{hi}: {m.sum() // 2} faces, pipeline {100 * before[m].mean():.2f} %, "
                  f"blend {100 * after[m].mean():.2f} %")


def whole_face(points_csv, names, sides, refined):
    """The 68-point NME of the pipeline, and with its brow and eye points replaced by `refined`."""
    points = read_points(points_csv, names, PIPELINE)
    truth = np.stack([points[k][0] for k in sides.keys])
    pipe = np.stack([points[k][1] for k in sides.keys])
    new = pipe.copy()
    r = refined.reshape(-1, 2, len(RIGHT), 2).copy()
    r[:, 1, :, 0] = sides.width - 1 - r[:, 1, :, 0]
    new[:, RIGHT], new[:, LEFT] = r[:, 0], r[:, 1]
    iod = np.linalg.norm(truth[:, 36] - truth[:, 45], axis=1)
    nme = lambda p: (np.linalg.norm(p - truth, axis=2).mean(1) / iod).mean()
    return nme(pipe), nme(new)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--faces", default="build/refine/faces.npz")
    p.add_argument("--data", default="build/region")
    p.add_argument("--out", default="build/region/net")
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--minutes", type=float, default=40)
    p.add_argument("--batch", type=int, default=64)
    p.add_argument("--widths", default="16,32,64,64,128")
    p.add_argument("--strides", default="2,2,2,1,2")
    p.add_argument("--hidden", type=int, default=256)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--profiled", help="the large-pose copies' folder (make_profiled_faces; DIR/S/faces.npz by load_faces.py), with "
                                      "DATA/profiled_points_S.csv (eval-landmarks DIR/S --points-out): joined to training and validation")
    p.add_argument("--expressions", metavar="CSV", help="label_dense's faces300w.csv: the net reads the side's brow shapes "
                                                         "too (EXPRESSIONS), trained on these labels")
    p.add_argument("--expression-weight", type=float, default=10.0)
    p.add_argument("--init", metavar="PT", help="start from this .best.pt (its last layer's rows for the points kept)")
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--evaluate", choices=["validation", "test"])
    p.add_argument("--export", action="store_true")
    p.add_argument("--region", choices=sorted(REGIONS), default="brows")
    p.add_argument("--brows-only", action="store_true",
                   help="the eyes' share 0: their points stay the pipeline's (the gaze stage's synthetic renders read worse with the net's)")
    a = p.parse_args()
    use_region(a.region)
    if a.export and (a.expressions or a.region != "brows"):
        raise SystemExit("--export: the refine stage runs the brows and eyes' net, 22 outputs a side (no brow readings)")
    setup_torch(a.threads)
    data = np.load(a.faces)
    names = list(data["names"])
    csv = lambda s: os.path.join(a.data, f"points_{s}.csv")
    points = {s: read_points(csv(s), names, PIPELINE) for s in ("train", "validation")}
    shapes = []
    for ann, _ in points["train"].values():
        left = ann[LEFT].copy()
        left[:, 0] = 255 - left[:, 0]
        shapes += [ann[RIGHT], left]
    mean = side_mean(shapes, a.size)
    labels = read_expression_labels(a.expressions) if a.expressions else None
    train = Sides(data["images"], points["train"], mean, points["train"].keys(), labels=labels, names=names)
    val = Sides(data["images"], points["validation"], mean, points["validation"].keys(), labels=labels, names=names)
    sets = [val]
    if a.profiled:
        for split in ("train", "validation"):
            copies = np.load(os.path.join(a.profiled, split, "faces.npz"))
            turned_points = read_points(os.path.join(a.data, f"profiled_points_{split}.csv"), list(copies["names"]), PIPELINE)
            turned = Sides(copies["images"], turned_points, mean, turned_points.keys(), by_box=True, labels=labels,
                           names=list(copies["names"]))
            if split == "train":
                train.join(turned)
            else:
                sets.append(turned)
    net = Refiner(a.size, widths=tuple(int(v) for v in a.widths.split(",")), strides=tuple(int(v) for v in a.strides.split(",")),
                  hidden=a.hidden)
    readings = len(EXPRESSIONS) if a.expressions else 0
    net.head[-1] = torch.nn.Linear(a.hidden, 2 * len(RIGHT) + readings)
    if a.init:
        start = torch.load(a.init)["net"]
        last = [k for k in start if k.startswith("head.") and k.endswith(".weight")][-1]
        own = net.state_dict()
        for k in (last, last.replace("weight", "bias")):
            rows = start[k].shape[0]
            own[k][:rows] = start[k]
            start[k] = own[k]
        net.load_state_dict(start)
    print(f"{len(train.truth)} training sides, {len(val.truth)} validation; {sum(p.numel() for p in net.parameters())} parameters",
          flush=True)
    if a.evaluate:
        saved = torch.load(a.out + ".best.pt")
        net.load_state_dict(saved["net"])
        share = shares(sets, [predict(net, v, mean, a.size)[0] for v in sets])
        if a.brows_only and a.region == "brows":
            share["eyes"] = 0.0
        sides, evaluated = val, points["validation"]
        if a.evaluate == "test":
            evaluated = read_points(csv("test"), names, PIPELINE)
            sides = Sides(data["images"], evaluated, mean, evaluated.keys(), labels=labels, names=names)
        refined, readings = predict(net, sides, mean, a.size)
        print("net's share (validation): " + ", ".join(f"{name} {share[name]:.2f}" for name, _ in PARTS))
        print(summary(f"{a.evaluate} pipeline", sides.init, sides))
        print(summary(f"{a.evaluate} net", refined, sides))
        print(summary(f"{a.evaluate} blend", blended(refined, sides, share), sides))
        if a.expressions:
            print(expression_summary(f"{a.evaluate} brow readings", readings, sides))
        before, after = whole_face(csv(a.evaluate), names, sides, blended(refined, sides, share))
        print(f"{a.evaluate} 68-point NME: pipeline {100 * before:.2f} %, with the blend {100 * after:.2f} %")
        by_turn(a.evaluate, evaluated, sides, refined, share)
        if a.evaluate == "validation" and len(sets) > 1:
            turned = sets[1]
            refined = predict(net, turned, mean, a.size)[0]
            for name, pts in (("pipeline", turned.init), ("net", refined), ("blend", blended(refined, turned, share))):
                print(summary(f"turned validation copies {name} (over sqrt(box))", pts, turned))
        if a.export:
            export_onnx(net, (1, 1, a.size, a.size), a.out + ".onnx", "offsets")
            w = point_shares(share)
            with open(a.out + ".side.txt", "w") as f:
                f.write(f"{a.size}\n" + " ".join(f"{v:.6f}" for v in mean.reshape(-1)) + "\n" + " ".join(f"{v:.2f}" for v in w) + "\n")
            print(f"wrote {a.out}.onnx and {a.out}.side.txt")
        return
    for v in sets:
        print(summary("validation pipeline" if v is val else "turned validation copies' pipeline (over sqrt(box))", v.init, v), flush=True)
    if a.expressions:  # the constant guess (the training median) the readings' error is measured against
        val_known = ~np.isnan(val.expr)
        guess_error = np.abs(np.nanmedian(train.expr, axis=0)[None] - val.expr)[val_known].mean()
    opt = torch.optim.AdamW(net.parameters(), lr=a.lr, weight_decay=1e-5)
    rng = np.random.default_rng(0)
    budget, began, seconds, epoch, best = a.minutes * 60, time.time(), 0.0, 0, None
    log = open(a.out + ".log", "a")
    while time.time() - began < budget:
        start_time = time.time()
        net.train()
        lr = a.lr * 0.5 * (1 + math.cos(math.pi * min(1.0, seconds / budget)))
        for g in opt.param_groups:
            g["lr"] = lr
        order = rng.permutation(len(train.truth))
        losses = []
        for start in range(0, len(order) - a.batch + 1, a.batch):
            x, target, _, _, expr = batch(train, order[start:start + a.batch], mean, a.size, rng, augment=True)
            y = net(x)
            loss = F.smooth_l1_loss(y[:, :target.shape[1]], target, beta=0.5)
            if a.expressions:
                known = ~torch.isnan(expr)
                loss = loss + a.expression_weight * F.smooth_l1_loss(y[:, target.shape[1]:][known], expr[known], beta=0.1)
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(loss.item())
        epoch += 1
        seconds += time.time() - start_time
        predicted = [predict(net, v, mean, a.size) for v in sets]
        refined = [points for points, _ in predicted]
        share = shares(sets, refined)
        now = score(sets, refined, share)
        reading = ""
        if a.expressions:  # the readings' mean absolute error over a constant guess's (the training median), added
            got = predicted[0][1]  # sets[0] is val
            now += np.abs(got - val.expr)[val_known].mean() / guess_error
            reading = expression_summary("readings", got, val) + "; "
        if best is None or now < best:
            best = now
            torch.save({"net": net.state_dict(), "mean": mean}, a.out + ".best.pt")
        turned = f"; turned copies' blend {summary('', blended(refined[1], sets[1], share), sets[1])}" if len(sets) > 1 else ""
        shares_now = ", ".join(f"{name} {share[name]:.2f}" for name, _ in PARTS)
        line = (f"epoch {epoch} lr {lr:.2e} loss {np.mean(losses):.4f} {summary('net', refined[0], val)}; blend "
                f"({shares_now}) {summary('', blended(refined[0], val, share), val)}{turned}; "
                f"{reading}score {now:.4f}, best {best:.4f} ({time.time() - start_time:.0f} s)")
        print(line, flush=True)
        log.write(line + "\n")
        log.flush()


if __name__ == "__main__":
    main()
