#!/usr/bin/python3
"""Trains the gaze stage's iris CNN (docs/gaze.md): from the normalised 40 x 28 eye
patch, per cell of a stride-2 grid (14 x 20; cell (j, i) is patch pixel (2i, 2j)) the
probabilities of skin, sclera and iris: the maps the MAP gaze fit reads, which the pixel
forest gives otherwise. The patches come from `train_eyes --samples-out DIR`; their classes are
MediaPipe's iris and eyelids (teacher labels, another model's predictions, not ground truth)
or, on renders of the face model, the renderer's exact classes.

  /usr/bin/python3 -m tools.train.eyes.train_iris_net [--samples build/eye_samples]
        [--out build/eyes/iris_net] [--minutes 10] [--synthetic-share 0.3]

Trains on DIR/train_* (300-W train crops, the training clips, the renders; eyes whose teacher
iris is not trusted are left out), reports on DIR/validation_* (300-W validation) and
DIR/heldout_* (the held-out clips d14 and franck), which are never trained on; the 300-W test
split is not in the folder at all. Logs each epoch to OUT.log; the learning rate decays to zero
over the time budget and the last epoch is kept (OUT.pt; no choosing among epochs by the held-out
figures) and exported as OUT.onnx (opset 13, eval mode, BatchNorm folded, softmax included: what
OpenCV 4.6's dnn loads).
"""
import argparse, copy, os, time

import numpy as np
import torch

from tools.train import nets


PATCH_H, PATCH_W = 28, 40
# The classified region of the patch (libfacetrack/src/gaze/eye_model_data.hpp, kClassifiedRegion):
# x 2..38, y 4..24 in patch pixels, i.e. grid columns 1..18 and rows 2..11.
REGION_COLS, REGION_ROWS = slice(1, 19), slice(2, 12)
SKIN, SCLERA, IRIS = 0, 1, 2


class IrisNet(torch.nn.Module):
    """1 x 28 x 40 -> 3 x 14 x 20 class scores: one full-resolution conv, one stride-2, then
    dilated convs (dilation 1, 2, 4) so that each cell sees about 33 patch pixels: the whole
    eye, which tells an iris from a dark lash line."""

    def __init__(self, width=16):
        super().__init__()

        def block(cin, cout, stride=1, dilation=1):
            return [torch.nn.Conv2d(cin, cout, 3, stride=stride, padding=dilation, dilation=dilation, bias=False),
                    torch.nn.BatchNorm2d(cout), torch.nn.ReLU()]

        self.features = torch.nn.Sequential(*block(1, 8), *block(8, width, stride=2), *block(width, width),
                                            *block(width, width, dilation=2), *block(width, width, dilation=4))
        self.head = torch.nn.Conv2d(width, 3, 1)

    def forward(self, x):
        return self.head(self.features(x))


class WithSoftmax(torch.nn.Module):
    def __init__(self, net):
        super().__init__()
        self.net = net

    def forward(self, x):
        return torch.softmax(self.net(x), dim=1)


def load(samples, name):
    """Patches (N x 1 x 28 x 40), the class of each grid cell (N x 14 x 20), and per eye
    (aperture, iris usable, synthetic)."""
    patches = np.load(os.path.join(samples, name + "_patches.npy"))
    classes = np.load(os.path.join(samples, name + "_classes.npy"))[:, ::2, ::2]
    info = np.load(os.path.join(samples, name + "_info.npy"))
    keep = info[:, 1] > 0.5
    return (torch.as_tensor(patches[keep][:, None].copy()), torch.as_tensor(classes[keep].astype(np.int64)),
            torch.as_tensor(info[keep]))


def scores(net, x, y):
    """Over the classified region: pixel accuracy, iris IoU, and the mean distance (patch pixels)
    between the iris-probability centroid and the labelled iris cells' centroid."""
    net.eval()
    with torch.no_grad():
        p = torch.cat([torch.softmax(net(x[i:i + 2048]), dim=1) for i in range(0, len(x), 2048)])
    p, y = p[:, :, REGION_ROWS, REGION_COLS], y[:, REGION_ROWS, REGION_COLS]
    predicted = p.argmax(dim=1)
    accuracy = (predicted == y).float().mean().item()
    both = ((predicted == IRIS) & (y == IRIS)).sum().item()
    either = ((predicted == IRIS) | (y == IRIS)).sum().item()
    rows = torch.arange(y.shape[1], dtype=torch.float32)[None, :, None]
    cols = torch.arange(y.shape[2], dtype=torch.float32)[None, None, :]

    def centroid(w):
        total = w.sum(dim=(1, 2)).clamp_min(1e-6)
        return torch.stack([(w * cols).sum(dim=(1, 2)) / total, (w * rows).sum(dim=(1, 2)) / total], dim=1)

    labelled = (y == IRIS).float()
    seen = labelled.sum(dim=(1, 2)) >= 2
    error = (centroid(p[:, IRIS]) - centroid(labelled)).norm(dim=1)[seen] * 2.0  # cells are 2 patch pixels
    return accuracy, both / max(either, 1), error.mean().item()


def lower_resolution(x, chosen):
    """The `chosen` patches of `x` as a smaller face's eye shows them: scaled down by one factor
    in 0.4-1 per batch (antialiased), then back up to the patch size, as the stage's cut upsamples."""
    if not chosen.any():
        return x
    factor = 0.4 + 0.6 * torch.rand(1).item()
    size = (max(4, round(PATCH_H * factor)), max(4, round(PATCH_W * factor)))
    small = torch.nn.functional.interpolate(x[chosen], size=size, mode="bilinear", align_corners=False, antialias=True)
    x = x.clone()
    x[chosen] = torch.nn.functional.interpolate(small, size=(PATCH_H, PATCH_W), mode="bilinear", align_corners=False)
    return x


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--samples", default="build/eye_samples", help="train_eyes --samples-out's folder")
    p.add_argument("--out", default="build/eyes/iris_net", help="OUT.onnx, OUT.pt, OUT.log")
    p.add_argument("--minutes", type=float, default=10.0, help="training time")
    p.add_argument("--synthetic-share", type=float, default=0.3, help="share of renders in each batch (0: teacher only)")
    p.add_argument("--width", type=int, default=16, help="channels of the dilated layers")
    p.add_argument("--noise", type=float, default=0.15, help="largest added pixel noise (normalised units)")
    p.add_argument("--blur", type=float, default=0.0,
                   help="share of each batch seen at a lower resolution (down by 0.4-1, then up): small faces' eyes")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()
    nets.setup_torch(a.threads, seed=a.seed)
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)

    x, y, info = load(a.samples, "train")
    synthetic = info[:, 2] > 0.5
    real_idx, synth_idx = torch.nonzero(~synthetic)[:, 0], torch.nonzero(synthetic)[:, 0]
    if a.synthetic_share <= 0:
        synth_idx = synth_idx[:0]
    held = {name: load(a.samples, name)[:2] for name in ("validation", "heldout")}
    print(f"train: {len(real_idx)} teacher-labelled eyes, {len(synth_idx)} renders; "
          f"validation {len(held['validation'][0])}, held-out clips {len(held['heldout'][0])}", flush=True)

    net = IrisNet(a.width)
    optimiser = torch.optim.AdamW(net.parameters(), lr=3e-3, weight_decay=1e-4)
    batch, per_epoch = 128, len(real_idx)
    share = a.synthetic_share if len(synth_idx) else 0.0
    started, epoch = time.time(), 0
    log = open(a.out + ".log", "w")
    log.write(f"# {vars(a)}\n")
    deadline = started + 60 * a.minutes
    while time.time() < deadline:
        epoch += 1
        net.train()
        n_synth = int(per_epoch * share / (1 - share)) if share > 0 else 0
        order = torch.cat([real_idx[torch.randperm(len(real_idx))],
                           synth_idx[torch.randint(len(synth_idx), (n_synth,))] if n_synth else real_idx[:0]])
        order = order[torch.randperm(len(order))]
        total, seen = 0.0, 0
        for k in range(0, len(order), batch):
            i = order[k:k + batch]
            xb = x[i]
            if a.blur > 0:
                xb = lower_resolution(xb, torch.rand(len(i)) < a.blur)
            xb = xb + torch.rand(len(i), 1, 1, 1) * a.noise * torch.randn(len(i), 1, PATCH_H, PATCH_W)
            loss = torch.nn.functional.cross_entropy(net(xb), y[i])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() * len(i)
            seen += len(i)
        elapsed = time.time() - started
        for group in optimiser.param_groups:  # cosine decay over the time budget
            group["lr"] = 3e-3 * 0.5 * (1 + np.cos(np.pi * min(1.0, elapsed / (60 * a.minutes))))
        v_acc, v_iou, v_err = scores(net, *held["validation"])
        h_acc, h_iou, h_err = scores(net, *held["heldout"])
        line = (f"epoch {epoch}: loss {total / seen:.4f}; 300-W validation accuracy {v_acc:.3f} iris IoU {v_iou:.3f} "
                f"centroid {v_err:.2f} px; held-out clips {h_acc:.3f} / {h_iou:.3f} / {h_err:.2f} px; {elapsed:.0f} s")
        print(line, flush=True)
        log.write(line + "\n")
        log.flush()
        torch.save({"state": net.state_dict(), "width": a.width, "epoch": epoch}, a.out + ".pt")

    export = WithSoftmax(copy.deepcopy(net).eval()).eval()
    nets.export_onnx(export, (1, 1, PATCH_H, PATCH_W), a.out + ".onnx", "classes")
    print(f"wrote {a.out}.onnx (epoch {epoch}, 300-W validation iris IoU {v_iou:.3f}, held-out clips {h_iou:.3f})", flush=True)


if __name__ == "__main__":
    main()
