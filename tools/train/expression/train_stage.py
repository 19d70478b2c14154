#!/usr/bin/python3
"""Trains one CNN cascade stage (docs/cnn.md): from the canonical face patch at a
start's parameters, the update to the label's parameters (pose about the face centre and 49
expressions: libfacetrack/src/expression/update_net.hpp, written by make_cnn_samples). The labels
are the dense teacher labels (MediaPipe's mesh fitted with the face model), and with --teacher
MediaPipe Face Landmarker's blendshape scores and the exact shapes of expression-warped copies
(class Teacher, load()): teacher labels, not ground truth. With --landmarks, the cascade's last
net instead: the 68 annotated 300-W points' displacements from the start's projected landmarks
(libfacetrack/src/expression/landmark_net.hpp), trained on the 300-W crops and their profiled
copies (the clips have no annotated points).

  /usr/bin/python3 -m tools.train.expression.train_stage [--samples build/cnn_samples]
        [--out build/cnn/stage1] [--minutes 30] [--epochs N] [--resume] [--landmarks | --expressions]
        [--teacher ../shared/data/teacher] [--copies-per-epoch K] [--clips-per-epoch K]

Trains on the samples whose split is "train" (300-W train crops, their profiled or warped copies,
the training people's clip frames and their warped copies): each epoch all the 300-W samples, the
copies (or --copies-per-epoch times as many, drawn afresh) and --clips-per-epoch times as many
clip samples, half of them mirrored (patch flipped, update mirrored, left and right shapes
swapped). It reports on the 300-W validation crops and their profiled copies, and with --teacher
on the validation people's frames and warped copies (data/clip_splits.csv); the 300-W test crops
and the held-out people are never read. Logs each epoch to OUT.log, keeps OUT.pt (resumable) and
OUT.best.pt (the epoch with the lowest error on the validation sets: rotation, points, or with
--expressions the expressions) and exports the best as OUT.onnx (opset 13, eval mode, BatchNorm
folded: what OpenCV 4.6's dnn loads); with --teacher also OUT.validation_{r,rest,gain}.txt for
pack_cnn.
"""
import argparse, copy, csv, math, os, sys, time

import numpy as np
import torch

from tools.train import nets



def load_all(loader, samples, name, splits):
    """`loader`'s sets from each of the comma-separated sample folders, concatenated."""
    parts = [t for t in (loader(d, name, splits) for d in samples.split(",")) if t is not None and len(t[0])]
    if not parts:
        return None
    return (torch.cat([t[0] for t in parts]), torch.cat([t[1] for t in parts]), parts[0][2],
            torch.cat([t[3] if len(t) > 3 else torch.ones_like(t[1]) for t in parts]),
            torch.cat([t[4] for t in parts]) if len(parts[0]) > 4 else None)


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


# Clips left out of training besides the held-out split (--hold-out-clips): substrings of the key.
HOLD_OUT_CLIPS = []


def kept(row, splits):
    return row[1] in splits and not any(c in row[0] for c in HOLD_OUT_CLIPS)


# Shapes MediaPipe's blendshape model never moves (../shared/data/teacher/README.md): its scores
# for them are no reading, so they are learnt from the dense labels alone, where a sample has them.
TEACHER_BLIND = {"cheekPuff", "noseSneerLeft", "noseSneerRight", "cheekSquintLeft", "cheekSquintRight", "jawForward", "tongueOut"}


def mirror_name(name):
    """The shape a face's mirror image shows for `name` (left and right swap)."""
    for a, b in (("_L", "_R"), ("Left", "Right")):
        if name.endswith(a): return name[:-len(a)] + b
        if name.endswith(b): return name[:-len(b)] + a
    return name


# Face-model expressions with a side whose ARKit shape has none (model/arkit_mapping.cpp averages the two).
UNSIDED_IN_ARKIT = ("browInnerUp", "cheekPuff")


def arkit_name(native):
    """The ARKit name of a face-model expression ("browDown_L" -> "browDownLeft", "browInnerUp_L" -> "browInnerUp")."""
    if native[:-2] in UNSIDED_IN_ARKIT and native[-2:] in ("_L", "_R"):
        return native[:-2]
    for suffix, side in (("_L", "Left"), ("_R", "Right")):
        if native.endswith(suffix):
            return native[:-len(suffix)] + side
    return native


class Teacher:
    """MediaPipe Face Landmarker's blendshape scores (../shared/data/teacher/*_blendshapes.csv:
    another model's predictions, not ground truth) by sample key, each shape relative to its rest
    level: w = clamp((s - s0) / (1 - s0), 0, 1), s0 the shape's median over the 300-W training
    crops (the teacher reads eyeSquint about 0.4 and browOuterUp up to 0.4 on relaxed faces)."""

    def __init__(self, folder):
        self.scores, self.rest = {}, {}
        train_crops = []
        for name, keyed in (("faces300w", lambda r: r["image"]), ("clips", lambda r: f"{r['clip']}#{r['frame']}")):
            with open(os.path.join(folder, name + "_blendshapes.csv")) as f:
                reader = csv.DictReader(f)
                shapes = reader.fieldnames[reader.fieldnames.index("_neutral") + 1:reader.fieldnames.index("m00")]
                for r in reader:
                    if r["face"] != "1":
                        continue
                    key = keyed(r)
                    self.scores[key] = {n: float(r[n]) for n in shapes}
                    if name == "faces300w" and "testset" not in key:
                        train_crops.append(self.scores[key])
        median = {n: float(np.median([c[n] for c in train_crops])) for n in train_crops[0]}
        for n in median:  # a pair alike: a face and its mirror image read alike
            self.rest[n] = (median[n] + median.get(mirror_name(n), median[n])) / 2

    def targets(self, key, names):
        """Per expression in `names` (face-model names), the teacher's weight, or NaN where it has none."""
        scores = self.scores.get(key)
        out = np.full(len(names), np.nan, dtype=np.float32)
        if scores is None:
            return None
        for k, n in enumerate(names):
            a = arkit_name(n)
            if a in scores and a not in TEACHER_BLIND:
                s0 = min(self.rest[a], 0.9)
                out[k] = min(max((scores[a] - s0) / (1.0 - s0), 0.0), 1.0)
        return out


TEACHER = None  # --teacher: a Teacher


def load(samples_dir, name, splits):
    """Patches (uint8), updates (start -> label, computed by make_cnn_samples) and per output a
    weight (1: a label; 0: none) of the samples in `splits`. With --teacher, each expression's label
    is the teacher's where it has a reading of the sample, else the sample's own label (the dense
    teacher labels of the 300-W crops); a clip frame tracked by make_cnn_samples --tracked-clips has
    no label of its own, so only the teacher's count, and a frame the teacher found no face in is dropped."""
    path = os.path.join(samples_dir, name + "_patches.npy")
    if not os.path.exists(path):
        return None
    patches = np.load(path, mmap_mode="r")
    header, rows = read_csv(os.path.join(samples_dir, name + "_samples.csv"))
    first = header.index("d_omega_x")
    columns = [c[2:] for c in header[first:]]
    keep = [i for i, r in enumerate(rows) if kept(r, splits)]
    update = np.array([[float(v) for v in rows[i][first:]] for i in keep], dtype=np.float32).reshape(len(keep), len(columns))
    weight = np.ones_like(update)
    names = columns[6:]
    start_columns = [header.index(n) for n in names]
    starts = np.array([[float(rows[i][c]) for c in start_columns] for i in keep], dtype=np.float32).reshape(len(keep), len(names))
    if TEACHER is not None:
        own_label = name not in ("clips", "clips_moved")  # tracked clip frames carry no label of their own
        label_columns = [header.index("label_" + n) for n in names]
        photographed = {}  # a warped copy's photograph: its label, by key (make_cnn_samples keys a copy "KEY@movedN")
        copies = name in ("moved", "clips_moved")
        if copies:
            base_header, base_rows = read_csv(os.path.join(samples_dir, ("faces300w" if name == "moved" else "clips") + "_samples.csv"))
            base_columns = [base_header.index("label_" + n) for n in names]
            for r in base_rows:
                photographed.setdefault(r[0], np.array([float(r[c]) for c in base_columns], dtype=np.float32))
        usable = []
        for j, i in enumerate(keep):
            key = rows[i][0].split("@")[0]
            teacher = TEACHER.targets(key, names)
            if copies:
                # The shapes expression warping changed are known exactly (in the face model's units);
                # the others are as the teacher read the photograph.
                label = np.array([float(rows[i][c]) for c in label_columns], dtype=np.float32)
                moved = np.abs(label - photographed[key]) > 1e-4 if key in photographed else np.ones(len(names), bool)
                teacher = np.full(len(names), np.nan, np.float32) if teacher is None else teacher
                teacher[moved] = label[moved]
            if teacher is None:
                continue
            seen = ~np.isnan(teacher)
            update[j, 6:][seen] = teacher[seen] - starts[j][seen]
            if not own_label:
                weight[j, 6:][~seen] = 0.0
            usable.append(j)
        keep = [keep[j] for j in usable]
        update, weight, starts = update[usable], weight[usable], starts[usable]
    labels = torch.as_tensor(starts + update[:, 6:])  # the label's expressions, absolute
    return torch.as_tensor(np.asarray(patches[keep])), torch.as_tensor(update), columns, torch.as_tensor(weight), labels


# A landmark displacement larger than this (patch pixels) comes from a start turned nearly
# edge-on, where the patch shows little of the face and the canonical map degenerates: not a
# sample to learn from.
MAX_DISPLACEMENT_PX = 24.0


def estimate_of(pred, update, labels):
    """The expressions as the stage reports them: the start (label - update) moved by the predicted
    update, clamped to [0, 1]."""
    return (labels - update[:, 6:] + pred[:, 6:]).clamp(0, 1)


def expression_agreement(pred, update, labels, names):
    """Per expression, Pearson r between estimate_of() and the label."""
    estimate = estimate_of(pred, update, labels)
    out = {}
    for k, n in enumerate(names):
        a, b = estimate[:, k] - estimate[:, k].mean(), labels[:, k] - labels[:, k].mean()
        denominator = (a.norm() * b.norm()).item()
        out[n] = (a @ b).item() / denominator if denominator > 1e-9 else float("nan")
    return out


def masked_agreement(estimate, labels, mask, names):
    """Per expression, Pearson r between estimate and label over the samples that have a label."""
    out = {}
    for k, n in enumerate(names):
        keep = mask[:, k] > 0
        a, b = estimate[keep, k] - estimate[keep, k].mean(), labels[keep, k] - labels[keep, k].mean()
        denominator = (a.norm() * b.norm()).item()
        out[n] = (a @ b).item() / denominator if keep.sum() > 10 and denominator > 1e-9 else float("nan")
    return out


# A gain above this would amplify noise more than it restores response.
MAX_GAIN = 3.0


def gains(estimate, labels, mask, rest, names):
    """Per expression, the gain g that brings the validation people's readings to their labels:
    with w' = clamp((w - w0) / (1 - w0)) the reading above its rest level w0, the least-squares
    g = sum(w' l) / sum(w'^2) over the labelled samples, clamped to [1, MAX_GAIN] (1 where a shape
    is too rare to tell). A net regresses rare, strong expressions of new faces towards the mean;
    this restores their size."""
    out = {}
    for k, n in enumerate(names):
        keep = mask[:, k] > 0
        w0 = min(rest[n], 0.9)
        w = ((estimate[keep, k] - w0) / (1 - w0)).clamp(0, 1)
        l = labels[keep, k]
        shown = (l > 0.3).sum().item()
        g = (w @ l).item() / max((w @ w).item(), 1e-9) if shown >= 10 else 1.0
        out[n] = min(max(g, 1.0), MAX_GAIN)
    return out


def write_gains(out, values):
    """OUT.validation_gain.txt: per expression, its gain on the validation people (pack_cnn --gain-from-validation)."""
    with open(out + ".validation_gain.txt", "w") as f:
        for n, v in values.items():
            f.write(f"{n} {v:.4f}\n")


def write_agreement(out, agreement):
    """OUT.validation_r.txt: per expression, r on the 300-W validation crops (pack_cnn reads it)."""
    with open(out + ".validation_r.txt", "w") as f:
        for n, r in agreement.items():
            f.write(f"{n} {r:.4f}\n")


# The share of faces at rest whose estimate stays under the rest level below.
REST_QUANTILE = 0.9


def rest_levels(pred, update, labels, names):
    """Per expression, how high the estimate reads on faces that do not show the shape: its 0.9
    quantile over the crops whose label is at most the label's median there."""
    estimate = estimate_of(pred, update, labels)
    out = {}
    for k, n in enumerate(names):
        at_rest = labels[:, k] <= labels[:, k].median()
        out[n] = estimate[at_rest, k].quantile(REST_QUANTILE).item()
    return out


def reading(pred, update, labels, mask):
    """(estimate_of(), label, mask) of the expressions."""
    return estimate_of(pred, update, labels), labels, mask[:, 6:]


def teacher_readings(net, validation, scale, mirror, names):
    """Per validation set, reading() as the stage reads it (mirror-averaged), and the rest levels
    on the 300-W crops."""
    readings, rest = {}, None
    for name, (x_val, y_val, labels_val, m_val) in validation.items():
        pred = predict(net, x_val, scale, mirror)
        readings[name] = reading(pred, y_val, labels_val, m_val)
        if name == "faces300w":
            rest = rest_levels(pred, y_val, labels_val, names)
    return readings, rest


def write_teacher_figures(out, readings, rest, names):
    """OUT.validation_{r,rest,gain}.txt from teacher_readings: r and gain on the validation people's
    frames and warped copies, the rest levels on the 300-W validation crops; and
    OUT.validation_r_frames.txt, r on the people's frames alone: what pack_cnn compares the geometry
    net's r on the same frames with."""
    people = [readings[n] for n in ("clips", "clips_moved") if n in readings]
    estimate, label, mask = (torch.cat([r[i] for r in people]) for i in range(3))
    write_agreement(out, masked_agreement(estimate, label, mask, names))
    if "clips" in readings:
        with open(out + ".validation_r_frames.txt", "w") as f:
            for n, r in masked_agreement(*readings["clips"], names).items():
                f.write(f"{n} {r:.4f}\n")
    write_rest_levels(out, rest)
    write_gains(out, gains(estimate, label, mask, rest, names))


def write_rest_levels(out, levels):
    """OUT.validation_rest.txt: per expression, its rest level on the 300-W validation crops
    (pack_cnn --rest-from-validation makes it the shape's neutral)."""
    with open(out + ".validation_rest.txt", "w") as f:
        for n, v in levels.items():
            f.write(f"{n} {v:.4f}\n")


def predict(net, x, scale, mirror=None):
    """The net's outputs for standardised patches `x`; with `mirror` (mirror_permutation's order and
    sign), averaged with its outputs for the mirror images, as the expression stage runs it."""
    with torch.no_grad():
        out = torch.cat([net(x[i:i + 512]) for i in range(0, len(x), 512)]) * scale
        if mirror is None:
            return out
        order, sign = mirror
        flipped = torch.cat([net(x[i:i + 512].flip(3)) for i in range(0, len(x), 512)]) * scale
        return (out + flipped[:, order] * sign) / 2


def load_landmarks(samples_dir, name, splits):
    """Patches and landmark displacements (make_cnn_samples' OUT/NAME_landmarks.npy) of the samples in `splits`."""
    path = os.path.join(samples_dir, name + "_landmarks.npy")
    if not os.path.exists(path):
        return None
    patches = np.load(os.path.join(samples_dir, name + "_patches.npy"), mmap_mode="r")
    targets = np.load(path)
    _, rows = read_csv(os.path.join(samples_dir, name + "_samples.csv"))
    size = np.linalg.norm(targets.reshape(len(targets), -1, 2), axis=2).max(1)
    keep = [i for i, r in enumerate(rows) if kept(r, splits) and size[i] <= MAX_DISPLACEMENT_PX]
    columns = [f"l_{axis}{i}" for i in range(targets.shape[1] // 2) for axis in "xy"]
    return torch.as_tensor(np.asarray(patches[keep])), torch.as_tensor(targets[keep]), columns


def landmark_mirror_permutation(samples_dir, columns):
    """Per displacement output, the output it becomes in the mirrored face, and its sign: point i
    goes to point m(i) (OUT/landmarks_mirror.txt), its x displacement negated."""
    with open(os.path.join(samples_dir, "landmarks_mirror.txt")) as f:
        mirror = [int(v) for v in f.read().split()]
    order = [2 * mirror[i // 2] + i % 2 for i in range(len(columns))]
    return torch.tensor(order), torch.tensor([-1.0, 1.0] * (len(columns) // 2))


def mirror_permutation(columns):
    """Per update output, the output it becomes in the mirrored face, and its sign: the rotation
    M R M with M = diag(-1, 1, 1) is the angle-axis (w_x, -w_y, -w_z), the centre's move (-c_x, c_y, c_z)
    (the face centre lies on the face's mirror plane); left and right shapes swap."""
    names = columns[6:]
    def swap(n):
        for a, b in (("_L", "_R"), ("Left", "Right")):
            if n.endswith(a): return n[:-len(a)] + b
            if n.endswith(b): return n[:-len(b)] + a
        return n
    order = [0, 1, 2, 3, 4, 5] + [6 + names.index(swap(n)) for n in names]
    sign = [1, -1, -1, -1, 1, 1] + [1] * len(names)
    return torch.tensor(order), torch.tensor(sign, dtype=torch.float32)


def standardise(patches):
    """uint8 patches -> per patch zero mean, unit (population) standard deviation: what the
    runtime does before the net."""
    return nets.standardise(patches.float()[:, None] / 255.0)


def export(net, path, scale=None, output="update"):
    """ONNX opset 13 in eval mode: BatchNorm folded into the convolutions, only Conv, Relu,
    Flatten and Gemm, which OpenCV 4.6's dnn loads. `scale`: per output, folded into the last
    layer, so that the file gives the update itself."""
    net = copy.deepcopy(net).eval()
    if scale is not None:
        with torch.no_grad():
            last = net.head[-1]
            last.weight.mul_(scale[:, None])
            last.bias.mul_(scale)
    nets.export_onnx(net, (1, 1, 64, 64), path, output)


def write_columns(out, columns):
    """The outputs' names beside the net (pack_cnn checks them)."""
    with open(out + ".columns.txt", "w") as f:
        f.write("\n".join(columns) + "\n")


class Stage(torch.nn.Module):
    """64x64 grey -> (6 + E): 3x3 conv blocks (BatchNorm, ReLU) of the given widths and strides, whose
    strides bring the patch to 4x4, then two linear layers."""

    def __init__(self, outputs, widths=(16, 32, 64, 96), hidden=256, dropout=0.0, strides=(2, 2, 2, 2)):
        super().__init__()
        if len(strides) != len(widths) or math.prod(strides) != 16:
            raise ValueError(f"strides {strides}: one per block, bringing 64 px to 4")
        layers, channels = [], 1
        for width, stride in zip(widths, strides):
            layers += [torch.nn.Conv2d(channels, width, 3, stride=stride, padding=1, bias=False), torch.nn.BatchNorm2d(width),
                       torch.nn.ReLU()]
            channels = width
        self.features = torch.nn.Sequential(*layers)
        self.head = torch.nn.Sequential(torch.nn.Flatten(), torch.nn.Linear(widths[-1] * 4 * 4, hidden), torch.nn.ReLU(),
                                        *([torch.nn.Dropout(dropout)] if dropout > 0 else []), torch.nn.Linear(hidden, outputs))

    def forward(self, x):
        return self.head(self.features(x))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--samples", default="build/cnn_samples", help="make_cnn_samples' folder, or several, comma-separated")
    p.add_argument("--out", default="build/cnn/stage1")
    p.add_argument("--minutes", type=float, default=30)
    p.add_argument("--epochs", type=int, default=0,
                   help="stop after this many epochs (with --resume, counted from the start); 0: by --minutes only")
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--resume", action="store_true")
    p.add_argument("--export-only", action="store_true", help="export OUT.pt's net (e.g. while it trains) and stop")
    p.add_argument("--from-onnx", default="", help="with --export-only: instead, the validation figures of this ONNX net "
                   "(e.g. a shipped file's, pack_cnn --export-net) as OUT.validation_*.txt; nothing exported")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--landmarks", action="store_true", help="train the landmark net (68 displacements) instead of a stage")
    p.add_argument("--expressions", action="store_true",
                   help="a stage that reads the expressions (pack_cnn --expressions-only): they weigh 20x the pose in the "
                        "loss and choose the best epoch; give samples whose starts are the fit's (make_cnn_samples "
                        "--starts-from fit), as at run time: starts near the label would teach corrections, not readings")
    p.add_argument("--dropout", type=float, default=0.0, help="dropout before the last layer (not in the export)")
    p.add_argument("--widths", default="16,32,64,96", help="the conv blocks' channels, comma-separated")
    p.add_argument("--strides", default="2,2,2,2",
                   help="the conv blocks' strides, comma-separated (their product 16); a first block of stride 1 reads the "
                        "patch at full resolution, where a lip corner moves by a pixel or two")
    p.add_argument("--hidden", type=int, default=256, help="the hidden linear layer's width")
    p.add_argument("--hold-out-clips", default="", help="clips also left out of training, comma-separated parts of their names")
    p.add_argument("--clips-per-epoch", type=float, default=1,
                   help="draw this many times as many clip samples as 300-W samples each epoch (at most the clips' count)")
    p.add_argument("--copies-per-epoch", type=float, default=0,
                   help="draw this many times as many copies (profiled, warped) as 300-W samples each epoch; 0: all")
    p.add_argument("--teacher", default="",
                   help="with --expressions: the folder of MediaPipe's blendshape scores (../shared/data/teacher), the "
                        "labels of the shapes it reads (class Teacher); samples from make_cnn_samples --tracked-clips")
    a = p.parse_args()
    HOLD_OUT_CLIPS.extend(c for c in a.hold_out_clips.split(",") if c)
    if a.teacher:
        global TEACHER
        TEACHER = Teacher(a.teacher)
        print("teacher rest levels: " + " ".join(f"{n} {v:.2f}" for n, v in TEACHER.rest.items() if v >= 0.03), flush=True)
    nets.setup_torch(a.threads, seed=1)
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)

    loader = load_landmarks if a.landmarks else load
    faces, profiled, moved, clips_moved, clips = (load_all(loader, a.samples, n, {"train"})
                                                  for n in ("faces300w", "profiled", "moved", "clips_moved", "clips"))
    sets = [t for t in (faces, profiled, moved, clips_moved, clips) if t is not None]
    columns = faces[2]
    x_train = torch.cat([t[0] for t in sets])
    y_train = torch.cat([t[1] for t in sets])
    m_train = torch.cat([t[3] for t in sets])  # per output: 1 where the sample has a label
    # The copies, turned or with shapes moved (make_cnn_samples --profiled, --expression-copies), count as one set.
    n_faces = len(faces[0])
    n_profiled = sum(len(t[0]) for t in (profiled, moved, clips_moved) if t is not None)
    n_clips = len(clips[0]) if clips is not None else 0
    validation = {}
    for name in ("faces300w", "profiled") + (("clips", "clips_moved") if a.teacher else ()):
        v = load_all(loader, a.samples, name, {"validation"})
        if v is None or len(v[0]) == 0:
            continue
        if not a.landmarks:  # the label's own patches count in training, not in these figures
            # (a tracked clip's frame has no label of its own: its start is the tracker's, as at run time)
            perturbed = v[1][:, :6].abs().sum(1) > 0 if name == "faces300w" else torch.ones(len(v[0]), dtype=torch.bool)
            v = (v[0][perturbed], v[1][perturbed], v[2], v[3][perturbed], v[4][perturbed])
        validation[name] = (standardise(v[0]), v[1], v[4] if a.expressions else None, v[3])
    flip_order, flip_sign = landmark_mirror_permutation(a.samples.split(",")[0], columns) if a.landmarks else mirror_permutation(columns)
    # The net regresses each output over its spread on the training targets (about 9x faster
    # to train than raw radians and depth fractions of very different sizes; export folds the
    # spread back in); the loss weighs outputs alike within pose and within expressions, the
    # expressions together a quarter as much as pose; displacements all alike.
    labelled = m_train.sum(0).clamp_min(1)
    mean = (y_train * m_train).sum(0) / labelled
    scale = ((((y_train - mean) * m_train) ** 2).sum(0) / labelled).sqrt().clamp_min(1e-3)
    if a.landmarks:
        weight = torch.ones(y_train.shape[1])
    elif a.expressions:  # 49 expressions together 20x as much as the pose's six outputs
        n_expr = y_train.shape[1] - 6
        weight = torch.cat([torch.ones(6), torch.full((n_expr,), 120.0 / n_expr)])
    else:
        weight = torch.cat([torch.ones(6), torch.full((y_train.shape[1] - 6,), 0.25)])
    weight = weight / weight.sum()
    output_name = "displacement" if a.landmarks else "update"
    print(f"training samples: {n_faces} 300-W, {n_profiled} profiled or moved, {n_clips} clip; validation "
          f"{ {k: len(v[0]) for k, v in validation.items()} }; outputs {y_train.shape[1]}", flush=True)

    widths = tuple(int(w) for w in a.widths.split(","))
    strides = tuple(int(s) for s in a.strides.split(","))
    net = Stage(y_train.shape[1], widths, a.hidden, a.dropout, strides)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3, weight_decay=1e-5)
    epoch, started, best = 0, time.time(), float("inf")
    if a.export_only and a.from_onnx:  # its outputs are the update itself: the spread is folded in
        with open(a.from_onnx, "rb") as f:
            net = nets.onnx_chain(f.read())
        write_columns(a.out, columns)
        if TEACHER is not None:
            ones = torch.ones(y_train.shape[1])
            write_teacher_figures(a.out, *teacher_readings(net, validation, ones, (flip_order, flip_sign), columns[6:]), columns[6:])
        print(f"wrote {a.out}.validation_*.txt of {a.from_onnx}", flush=True)
        return
    if a.export_only:
        state = torch.load(a.out + (".best.pt" if os.path.exists(a.out + ".best.pt") else ".pt"))
        # the layers it was trained with
        net = Stage(y_train.shape[1], state.get("widths", widths), state.get("hidden", a.hidden), state.get("dropout", a.dropout),
                    state.get("strides", (2,) * len(state.get("widths", widths))))
        net.load_state_dict(state["net"])
        # The spread the net was trained with (older checkpoints lack it: then the given samples' own,
        # which must be the training run's --samples).
        export(net, a.out + ".onnx", state.get("scale", scale), output_name)
        write_columns(a.out, columns)
        net.eval()
        if TEACHER is not None:
            write_teacher_figures(a.out, *teacher_readings(net, validation, state.get("scale", scale), (flip_order, flip_sign),
                                                           columns[6:]), columns[6:])
        elif a.expressions and "faces300w" in validation:
            x_val, y_val, labels_val, _ = validation["faces300w"]
            write_rest_levels(a.out, rest_levels(predict(net, x_val, state.get("scale", scale), (flip_order, flip_sign)),
                                                 y_val, labels_val, columns[6:]))
        print(f"wrote {a.out}.onnx", flush=True)
        return
    if a.resume and os.path.exists(a.out + ".pt"):
        state = torch.load(a.out + ".pt")
        net.load_state_dict(state["net"]); opt.load_state_dict(state["opt"]); epoch = state["epoch"]
        best = state.get("best", best)
        print(f"resumed at epoch {epoch}", flush=True)
    log = open(a.out + ".log", "a")
    deadline = started + 60 * a.minutes
    while time.time() < deadline and (a.epochs <= 0 or epoch < a.epochs):
        net.train()
        # All 300-W samples, all copies (or --copies-per-epoch times as many as 300-W ones, drawn
        # afresh) and --clips-per-epoch times as many clip samples as 300-W ones (a clip's frames are alike).
        start_clips = n_faces + n_profiled
        order = torch.randperm(n_faces)
        copies = n_profiled if a.copies_per_epoch <= 0 else min(n_profiled, int(a.copies_per_epoch * n_faces))
        if n_profiled:
            order = torch.cat([order, n_faces + (torch.randperm(n_profiled)[:copies])])
        if n_clips:
            order = torch.cat([order, start_clips + torch.randint(n_clips, (int(a.clips_per_epoch * min(n_faces, n_clips)),))])
        order = order[torch.randperm(len(order))]
        total = 0.0
        for i in range(0, len(order), a.batch):
            idx = order[i:i + a.batch]
            x, y, m = standardise(x_train[idx]), y_train[idx], m_train[idx]
            flip = torch.rand(len(idx)) < 0.5
            x[flip] = x[flip].flip(3)
            y[flip] = y[flip][:, flip_order] * flip_sign
            m[flip] = m[flip][:, flip_order]
            if torch.rand(1).item() < 0.5:  # photometric: contrast and brightness on the standardised patch
                x = x * (0.8 + 0.4 * torch.rand(len(idx), 1, 1, 1)) + 0.2 * torch.randn(len(idx), 1, 1, 1)
            loss = ((((net(x) - y / scale) ** 2) * m).sum(0) / m.sum(0).clamp_min(1) * weight).sum()
            opt.zero_grad(); loss.backward(); opt.step()
            total += loss.item() * len(idx)
            if (i // a.batch) % 100 == 99:
                print(f"  epoch {epoch + 1}: {i + len(idx)} / {len(order)} samples, loss {total / (i + len(idx)):.4f}, "
                      f"{time.time() - started:.0f} s", flush=True)
        epoch += 1
        net.eval()
        line = f"epoch {epoch} train loss {total / len(order):.4f}; validation"
        score = float("inf")
        with torch.no_grad():
            readings = {}  # teacher mode: per validation set, (estimate, label, mask) of the expressions
            for name, (x_val, y_val, labels_val, m_val) in validation.items():
                pred = predict(net, x_val, scale, None if a.landmarks else (flip_order, flip_sign))
                if a.landmarks:  # mean point distance, patch pixels
                    before = y_val.view(len(y_val), -1, 2).norm(dim=2).mean().item()
                    after = (pred - y_val).view(len(y_val), -1, 2).norm(dim=2).mean().item()
                    if name == "faces300w":
                        score = after
                    line += f" {name}: point error {before:.3f} -> {after:.3f} patch px;"
                    continue
                rot_before = y_val[:, :3].norm(dim=1) * 180 / math.pi
                rot_after = (pred[:, :3] - y_val[:, :3]).norm(dim=1) * 180 / math.pi
                shift_before = y_val[:, 3:6].norm(dim=1).mean().item() * 100
                shift_after = (pred[:, 3:6] - y_val[:, 3:6]).norm(dim=1).mean().item() * 100
                m_expr = m_val[:, 6:]
                expr_before = ((y_val[:, 6:].abs() * m_expr).sum() / m_expr.sum().clamp_min(1)).item()
                expr_after = (((pred[:, 6:] - y_val[:, 6:]).abs() * m_expr).sum() / m_expr.sum().clamp_min(1)).item()
                if TEACHER is not None:
                    readings[name] = reading(pred, y_val, labels_val, m_val)
                    if name == "faces300w":
                        rest = rest_levels(pred, y_val, labels_val, columns[6:])
                if name == "faces300w":
                    score = expr_after if a.expressions else rot_after.mean().item()
                    if a.expressions and TEACHER is None:
                        agreement = expression_agreement(pred, y_val, labels_val, columns[6:])
                        line += " r " + " ".join(f"{n} {agreement[n]:.2f}" for n in ("browDown_L", "browInnerUp_L", "mouthPucker", "mouthFunnel"))
                        if score < best:
                            write_agreement(a.out, agreement)
                            write_rest_levels(a.out, rest_levels(pred, y_val, labels_val, columns[6:]))
                line += (f" {name}: rotation {rot_before.mean():.2f} -> {rot_after.mean():.2f} deg (within 3 deg "
                         f"{(rot_before < 3).float().mean() * 100:.0f} -> {(rot_after < 3).float().mean() * 100:.0f} %), "
                         f"centre {shift_before:.2f} -> {shift_after:.2f} % of depth, expression MAE {expr_before:.4f} -> {expr_after:.4f};")
        if readings:
            # Every validation set alike: the 300-W crops, the validation people's clip frames and
            # their warped copies.
            score = sum(((e - l).abs() * m).sum().item() / max(m.sum().item(), 1) for e, l, m in readings.values()) / len(readings)
            people = [readings[n] for n in ("clips", "clips_moved") if n in readings]
            estimate, label, mask = (torch.cat([r[i] for r in people]) for i in range(3))
            agreement = masked_agreement(estimate, label, mask, columns[6:])
            line += f" score {score:.4f}; validation people r " + " ".join(
                f"{n} {agreement[n]:.2f}" for n in ("jawOpen", "mouthSmile_L", "mouthPucker", "browDown_L", "browInnerUp_L", "mouthFrown_L",
                                                    "mouthPress_L", "mouthLeft", "cheekPuff_L", "noseSneer_L"))
            if score < best:
                write_teacher_figures(a.out, readings, rest, columns[6:])
        line += f" {time.time() - started:.0f} s"
        print(line, flush=True); log.write(line + "\n"); log.flush()
        torch.save({"net": net.state_dict(), "opt": opt.state_dict(), "epoch": epoch, "best": best, "scale": scale,
                    "dropout": a.dropout, "widths": widths, "strides": strides, "hidden": a.hidden}, a.out + ".pt")
        if score < best:  # the net that exports: the best on the validation crops (the test crops choose nothing)
            best = score
            torch.save({"net": net.state_dict(), "epoch": epoch, "scale": scale, "dropout": a.dropout, "widths": widths,
                        "strides": strides, "hidden": a.hidden}, a.out + ".best.pt")
    if os.path.exists(a.out + ".best.pt"):
        net.load_state_dict(torch.load(a.out + ".best.pt")["net"])
    net.eval()

    export(net, a.out + ".onnx", scale, output_name)
    write_columns(a.out, columns)
    print(f"wrote {a.out}.onnx", flush=True)


if __name__ == "__main__":
    main()
