#!/usr/bin/python3
"""Trains the expression stage's lip net (docs/cnn.md): from a 64 px mouth patch aligned by the 68
tracked points, the 40 lip points of MediaPipe Face Landmarker's mesh (tools/data/label_teacher_mesh.sh:
another model's predictions, not ground truth). That model's blendshapes, which the expression stage
learns from, are read off those points; the 68 points have 20 on the lips and miss most of a pucker,
a funnel or a rolled lip.

  /usr/bin/python3 -m tools.train.expression.train_lips --tracked build/tracked --tracked-crops build/tracked_300w \\
        --mesh build/teacher_mesh [--out build/cnn/lips] [--minutes 12]

The training people's tracked frames and the 300-W training crops train it (and their mirror
images); the validation people's frames and crops choose its epoch; the held-out people's clips are
never read. Writes OUT.onnx (batch 2: a patch and its mirror image, as the stage runs it),
OUT.npz (per tracked frame and crop of the training and validation sets, by key: the teacher's lip
points and the net's, mirror-averaged, in the geometry features' normalised frame, for
train_geometry.py --lips) and OUT.log.

The patch (expression/lip_net.hpp computes the same): with the 68 points' normalising frame of the
geometry features (centre c, angle theta of the eyes' line, root-mean-square size s), the anchor
a = (0, mean normalised y of points 48-67), patch pixel u (0-based) shows the frame point
    p(u) = c + s R(theta) (a + H ((2 u + 1) / S - 1)),   S = 64 pixels, H = 0.75,
bilinear with borders replicated; the net regresses each lip point's (q - a) / H, q its normalised
position.
"""
import argparse, os, subprocess, sys, time

import numpy as np
import torch

from tools.train import nets
from tools.train.expression import train_geometry as geometry
from tools.train.refine.load_faces import decode_gray
from tools.train.refine.train_refine import photometric

SIZE, HALF = 64, 0.75
# Face Landmarker mesh indices: the outer lip line from the right corner (61) over the upper lip and
# back under the lower one, then the inner line from its right corner (78) the same way.
LIPS = [61, 185, 40, 39, 37, 0, 267, 269, 270, 409, 291, 375, 321, 405, 314, 17, 84, 181, 91, 146,
        78, 191, 80, 81, 82, 13, 312, 311, 310, 415, 308, 324, 318, 402, 317, 14, 87, 178, 88, 95]
_PAIRS = {61: 291, 185: 409, 40: 270, 39: 269, 37: 267, 0: 0, 375: 146, 321: 91, 405: 181, 314: 84, 17: 17,
          78: 308, 191: 415, 80: 310, 81: 311, 82: 312, 13: 13, 324: 95, 318: 88, 402: 178, 317: 87, 14: 14}
_PAIRS.update({b: a for a, b in _PAIRS.items()})
LIPS_MIRROR = [LIPS.index(_PAIRS[i]) for i in LIPS]  # lip point k of the mirror image is point LIPS_MIRROR[k]


def anchor(q):
    """a above, from the 68 normalised points q (68 x 2)."""
    return np.array([0.0, q[48:68, 1].mean()])


def patch_map(points):
    """(A, t): patch pixel u -> frame point A u + t, and the anchor a, for the 68 points (68 x 2)."""
    c, unroll, s = geometry.normalising_frame(points[None])
    a = anchor(geometry.normalised(points[None], c, unroll, s)[0])
    roll = unroll[0].T  # R(theta)
    A = s[0] * roll * (2 * HALF / SIZE)
    t = c[0] + s[0] * roll @ (a + HALF * (1.0 / SIZE - 1))
    return A, t, a


def sample(gray, A, t):
    """The patch: pixel u shows gray at A u + t (pixel centres 0-based), bilinear, borders replicated."""
    u = np.arange(SIZE, dtype=np.float64)
    ux, uy = np.meshgrid(u, u)
    x = A[0, 0] * ux + A[0, 1] * uy + t[0]
    y = A[1, 0] * ux + A[1, 1] * uy + t[1]
    h, w = gray.shape
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    at = lambda yy, xx: gray[np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)].astype(np.float64)
    v = (at(y0, x0) * (1 - fx) * (1 - fy) + at(y0, x0 + 1) * fx * (1 - fy) + at(y0 + 1, x0) * (1 - fx) * fy +
         at(y0 + 1, x0 + 1) * fx * fy)
    return np.clip(np.rint(v), 0, 255).astype(np.uint8)


def decode_clip(path):
    """Every frame of a clip, grey, as ffmpeg decodes it (the frames the teachers read)."""
    w, h = map(int, subprocess.run(["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=width,height",
                                    "-of", "csv=p=0", path], capture_output=True, text=True, check=True).stdout.split(","))
    raw = subprocess.run(["ffmpeg", "-v", "error", "-i", path, "-f", "rawvideo", "-pix_fmt", "gray", "-vsync", "0", "-"],
                         capture_output=True, check=True).stdout
    return np.frombuffer(raw, np.uint8).reshape(-1, h, w)


def read_mesh(folder):
    """key -> the teacher's 478 points (x, y), in pixel-centre coordinates (its x, y put 0 at the left edge)."""
    import csv
    out = {}
    for name, key_of in (("faces300w", lambda r: r["image"]), ("clips", lambda r: f"{r['clip']}#{r['frame']}")):
        mesh = np.load(os.path.join(folder, name + "_mesh.npy"), mmap_mode="r")
        with open(os.path.join(folder, name + ".csv")) as f:
            for i, r in enumerate(csv.DictReader(f)):
                if r["face"] == "1":
                    out[key_of(r)] = np.asarray(mesh[i, :, :2], np.float64) - 0.5
    return out


def tracked_samples(a, which):
    """[(key, 68 points)] of the tracked frames of the clips of split `which` and of the crops of `which`."""
    out = []
    for file in sorted(os.listdir(a.tracked)):
        clip = file[:-len(".jsonl")] + ".mp4"
        if file.endswith(".jsonl") and a.splits.get(clip, "train") == which:
            out += [(f"{clip}#{r['frame']}", p) for _, r, p in geometry.tracked_lines(os.path.join(a.tracked, file))]
    if a.tracked_crops:
        with open(os.path.join(a.tracked_crops, which + ".txt")) as f:
            keys = f.read().split()
        out += [(keys[i], p) for i, _, p in geometry.tracked_lines(os.path.join(a.tracked_crops, which + ".jsonl"))]
    return out


def build(a, which, mesh):
    """Patches, lip targets ((q - a) / H, 40 x 2; NaN without the teacher's), keys, the anchors."""
    patches, targets, keys, anchors = [], [], [], []
    video_name, video = None, None
    samples = tracked_samples(a, which)
    for n, (key, points) in enumerate(samples):
        if "#" in key:
            clip, frame = key.split("#")
            if clip != video_name:
                video_name, video = clip, decode_clip(os.path.join(a.clips, clip))
            gray = video[int(frame)]
        else:
            gray = decode_gray(os.path.join(a.faces, key))
        A, t, anc = patch_map(points)
        patches.append(sample(gray, A, t))
        lips = np.full((40, 2), np.nan)
        if key in mesh:
            lips = (geometry.normalised(mesh[key][LIPS][None], *geometry.normalising_frame(points[None]))[0] - anc) / HALF
        targets.append(lips)
        keys.append(key)
        anchors.append(anc)
        if (n + 1) % 500 == 0 or n + 1 == len(samples):
            print(f"\r{which}: {n + 1}/{len(samples)} patches", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return np.array(patches), np.array(targets, np.float32), keys, np.array(anchors, np.float32)


def mirrored(patches, lips):
    """The mirror images' patches and lip targets (x negated about the anchor, points renumbered)."""
    lips = lips[:, LIPS_MIRROR].clone()
    lips[..., 0] *= -1
    return patches.flip(-1), lips


class LipNet(torch.nn.Sequential):
    """64 px grey -> 80 values: four stride-2 3x3 conv blocks of `widths` channels (BatchNorm, ReLU), `hidden` units."""

    def __init__(self, widths, hidden):
        layers, inputs = [], 1
        for width in widths:
            layers += [torch.nn.Conv2d(inputs, width, 3, 2, 1), torch.nn.BatchNorm2d(width), torch.nn.ReLU()]
            inputs = width
        super().__init__(*layers, torch.nn.Flatten(), torch.nn.Linear(widths[-1] * (SIZE // 16) ** 2, hidden), torch.nn.ReLU(),
                         torch.nn.Dropout(0.2), torch.nn.Linear(hidden, 80))


def predict(net, patches):
    """Mirror-averaged, as the stage runs it: (f(P) + M f(mirror P)) / 2, (N, 40, 2)."""
    net.eval()
    with torch.no_grad():
        x = nets.standardise(patches.float() / 255.0)
        direct = net(x).reshape(-1, 40, 2)
        flipped = net(x.flip(-1)).reshape(-1, 40, 2)[:, LIPS_MIRROR]
        flipped[..., 0] *= -1
        return (direct + flipped) / 2


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tracked", required=True, help="the folder of tracked clips (facetrack track --raw, one per clip)")
    p.add_argument("--tracked-crops", default="", help="the 300-W crops as tools/data/track_faces300w.sh tracked them")
    p.add_argument("--mesh", required=True, help="tools/data/label_teacher_mesh.sh's folder")
    p.add_argument("--clips", default="../shared/data/clips")
    p.add_argument("--faces", default="../shared/data/faces300w")
    p.add_argument("--out", default="build/cnn/lips")
    p.add_argument("--minutes", type=float, default=12)
    p.add_argument("--widths", default="8,16,32,64", help="the four conv blocks' channels")
    p.add_argument("--hidden", type=int, default=128)
    p.add_argument("--samples", default="build/cnn/lips_samples.npz",
                   help="the patches and targets, made here when the file is missing (delete it to remake them)")
    a = p.parse_args()
    a.splits = geometry.read_splits()
    nets.setup_torch(2, seed=1)
    if not os.path.exists(a.samples):
        mesh = read_mesh(a.mesh)
        built = {which: build(a, which, mesh) for which in ("train", "validation")}
        np.savez(a.samples, **{f"{which}_{part}": np.asarray(v) for which, parts in built.items()
                              for part, v in zip(("patches", "lips", "keys", "anchors"), parts)})
    with np.load(a.samples) as f:
        sets = {which: tuple(f[f"{which}_{part}"] for part in ("patches", "lips", "keys", "anchors")) for which in ("train", "validation")}
    train_patches = torch.tensor(sets["train"][0])
    train_lips = torch.tensor(sets["train"][1])
    labelled = ~torch.isnan(train_lips).any(2).any(1)
    train_patches, train_lips = train_patches[labelled], train_lips[labelled]
    val_patches, val_lips = torch.tensor(sets["validation"][0]), torch.tensor(sets["validation"][1])
    val_labelled = ~torch.isnan(val_lips).any(2).any(1)
    print(f"{len(train_patches)} training patches, {int(val_labelled.sum())} validation", flush=True)
    net = LipNet(tuple(int(w) for w in a.widths.split(",")), a.hidden)
    opt = torch.optim.AdamW(net.parameters(), lr=2e-3, weight_decay=1e-3)
    rng = np.random.default_rng(1)
    start, epoch, best, best_state = time.time(), 0, float("inf"), None
    while time.time() - start < a.minutes * 60:
        net.train()
        epoch += 1
        for idx in torch.randperm(len(train_patches)).split(128):
            x, y = train_patches[idx].float()[:, None] / 255.0, train_lips[idx].clone()
            flip = torch.rand(len(idx)) < 0.5
            x[flip], y[flip] = mirrored(x[flip], y[flip])
            # the alignment's error: a shift of up to 2 pixels, the targets moved with it
            dx, dy = (int(v) for v in rng.integers(-2, 3, 2))
            x = torch.roll(x, (dy, dx), (2, 3))
            y = y + torch.tensor([dx, dy]) * (2.0 / SIZE)  # a patch pixel is 2 / S in (q - a) / H units
            loss = torch.nn.functional.smooth_l1_loss(net(nets.standardise(photometric(x, rng))), y.reshape(len(y), -1), beta=0.02)
            opt.zero_grad()
            loss.backward()
            opt.step()
        error = (predict(net, val_patches[val_labelled][:, None]) - val_lips[val_labelled]).norm(dim=2).mean().item()
        if error < best:
            best, best_state = error, {k: v.clone() for k, v in net.state_dict().items()}
        print(f"epoch {epoch} loss {loss.item():.4f} validation mean point error {error:.4f} (patch half-widths)", flush=True)
    net.load_state_dict(best_state)
    nets.export_onnx(net, (2, 1, SIZE, SIZE), a.out + ".onnx", "lips")
    out = {}
    for which, (patches, lips, keys, anchors) in sets.items():
        predicted = predict(net, torch.tensor(patches)[:, None]).numpy()
        out[which + "_keys"] = keys
        # in the normalised frame of the geometry features: q = a + H (q - a) / H
        out[which + "_teacher"] = anchors[:, None, :] + HALF * lips
        out[which + "_net"] = anchors[:, None, :] + HALF * predicted
    np.savez(a.out + ".npz", **out)
    print(f"best validation mean point error {best:.4f} patch half-widths; wrote {a.out}.onnx and {a.out}.npz", flush=True)


if __name__ == "__main__":
    main()
