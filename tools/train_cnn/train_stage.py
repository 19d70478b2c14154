#!/usr/bin/python3
"""Trains one CNN cascade stage (issue 17, docs/cnn.md): from the canonical face patch at a
start's parameters, the update to the dense teacher label's parameters (pose and 49 expressions).
The labels are MediaPipe's predictions fitted with the face model: teacher labels, not ground truth.

  /usr/bin/python3 tools/train_cnn/train_stage.py [--samples build/cnn_samples] [--labels build/dense_labels]
        [--out build/cnn/stage1] [--minutes 30] [--resume]

Trains on the samples whose split is "train" (300-W train crops, training clips); reports on the
300-W validation crops; the 300-W test crops and the held-out clips (d14, franck) are never read.
Logs each epoch (losses, seconds) to OUT.log, keeps OUT.pt (resumable) and exports OUT.onnx
(opset 13, eval mode, BatchNorm folded: what OpenCV 4.6's dnn loads).
"""
import argparse, csv, math, os, sys, time

import numpy as np
import torch

torch.set_flush_denormal(True)  # about 9x faster for small nets on this CPU


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def load(samples_dir, labels_dir, name, splits):
    """Patches, starts and targets (label - start) of the samples in `splits`."""
    patches = np.load(os.path.join(samples_dir, name + "_patches.npy"), mmap_mode="r")
    header, rows = read_csv(os.path.join(samples_dir, name + "_samples.csv"))
    lheader, lrows = read_csv(os.path.join(labels_dir, name + ".csv"))
    columns = header[3:]  # omega x3, t x3, expressions
    lindex = [lheader.index(c) for c in columns]
    labels = {r[0]: np.array([float(r[i]) for i in lindex], dtype=np.float32) for r in lrows}
    keep = [i for i, r in enumerate(rows) if r[1] in splits]
    start = np.array([[float(v) for v in rows[i][3:]] for i in keep], dtype=np.float32)
    label = np.stack([labels[rows[i][0]] for i in keep])
    return np.asarray(patches[keep]), start, label, columns


def targets(start, label):
    """Rotation update as the angle-axis of R_label R_start^T, translation update over the depth,
    expression update: what a stage regresses."""
    def rot(w):
        w = torch.as_tensor(w)
        theta = w.norm(dim=1, keepdim=True).clamp_min(1e-12)
        k = w / theta
        K = torch.zeros(w.shape[0], 3, 3)
        K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
        K = K - K.transpose(1, 2)
        s, c = torch.sin(theta)[:, :, None], torch.cos(theta)[:, :, None]
        return torch.eye(3) + s * K + (1 - c) * K @ K
    r = rot(label[:, :3]) @ rot(start[:, :3]).transpose(1, 2)
    angle = torch.acos(((r.diagonal(dim1=1, dim2=2).sum(1) - 1) / 2).clamp(-1, 1))
    axis = torch.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], 1)
    dw = axis / (2 * torch.sin(angle).clamp_min(1e-9))[:, None] * angle[:, None]
    dt = torch.as_tensor((label[:, 3:6] - start[:, 3:6]) / start[:, 5:6])
    db = torch.as_tensor(label[:, 6:] - start[:, 6:])
    return torch.cat([dw, dt, db], 1).float()


def standardise(patches):
    """Per patch: zero mean, unit standard deviation (the runtime does the same before the net)."""
    x = torch.as_tensor(patches, dtype=torch.float32)[:, None] / 255.0
    mean = x.mean(dim=(2, 3), keepdim=True)
    std = x.std(dim=(2, 3), keepdim=True).clamp_min(1e-3)
    return (x - mean) / std


def export(net, path):
    """ONNX opset 13 in eval mode: BatchNorm folded into the convolutions, only Conv, Relu,
    Flatten and Gemm, which OpenCV 4.6's dnn loads."""
    net.eval()
    torch.onnx.export(net, torch.zeros(1, 1, 64, 64), path, opset_version=13, input_names=["patch"], output_names=["update"],
                      do_constant_folding=True, training=torch.onnx.TrainingMode.EVAL)


class Stage(torch.nn.Module):
    """64x64 grey -> (6 + E): four stride-2 conv blocks (BatchNorm, ReLU), two linear layers."""

    def __init__(self, outputs, widths=(16, 32, 64, 96), hidden=256):
        super().__init__()
        layers, channels = [], 1
        for width in widths:
            layers += [torch.nn.Conv2d(channels, width, 3, stride=2, padding=1, bias=False), torch.nn.BatchNorm2d(width),
                       torch.nn.ReLU()]
            channels = width
        self.features = torch.nn.Sequential(*layers)
        self.head = torch.nn.Sequential(torch.nn.Flatten(), torch.nn.Linear(widths[-1] * 4 * 4, hidden), torch.nn.ReLU(),
                                        torch.nn.Linear(hidden, outputs))

    def forward(self, x):
        return self.head(self.features(x))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--samples", default="build/cnn_samples")
    p.add_argument("--labels", default="build/dense_labels")
    p.add_argument("--out", default="build/cnn/stage1")
    p.add_argument("--minutes", type=float, default=30)
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--resume", action="store_true")
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(1)
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)

    train = [load(a.samples, a.labels, n, {"train"}) for n in ("faces300w", "clips")]
    val = load(a.samples, a.labels, "faces300w", {"validation"})
    columns = train[0][3]
    x_train = standardise(np.concatenate([t[0] for t in train]))
    y_train = targets(np.concatenate([t[1] for t in train]), np.concatenate([t[2] for t in train]))
    x_val, y_val = standardise(val[0]), targets(val[1], val[2])
    # Each output's spread on the training targets: the loss weighs them alike.
    scale = y_train.std(0).clamp_min(1e-3)
    print(f"{len(x_train)} training samples, {len(x_val)} validation; outputs {y_train.shape[1]}", flush=True)

    net = Stage(y_train.shape[1])
    opt = torch.optim.Adam(net.parameters(), lr=1e-3, weight_decay=1e-5)
    epoch, started = 0, time.time()
    if a.resume and os.path.exists(a.out + ".pt"):
        state = torch.load(a.out + ".pt")
        net.load_state_dict(state["net"]); opt.load_state_dict(state["opt"]); epoch = state["epoch"]
        print(f"resumed at epoch {epoch}", flush=True)
    log = open(a.out + ".log", "a")
    deadline = started + 60 * a.minutes
    while time.time() < deadline:
        net.train()
        order = torch.randperm(len(x_train))
        total = 0.0
        for i in range(0, len(order), a.batch):
            idx = order[i:i + a.batch]
            x = x_train[idx]
            if torch.rand(1).item() < 0.5:  # photometric: contrast and brightness on the standardised patch
                x = x * (0.8 + 0.4 * torch.rand(len(idx), 1, 1, 1)) + 0.2 * torch.randn(len(idx), 1, 1, 1)
            loss = (((net(x) - y_train[idx]) / scale) ** 2).mean()
            opt.zero_grad(); loss.backward(); opt.step()
            total += loss.item() * len(idx)
        epoch += 1
        net.eval()
        with torch.no_grad():
            pred = torch.cat([net(x_val[i:i + 512]) for i in range(0, len(x_val), 512)])
            before = ((y_val / scale) ** 2).mean().item()
            after = (((pred - y_val) / scale) ** 2).mean().item()
            rot_before = y_val[:, :3].norm(dim=1).mean().item() * 180 / math.pi
            rot_after = (pred[:, :3] - y_val[:, :3]).norm(dim=1).mean().item() * 180 / math.pi
            expr_before = y_val[:, 6:].abs().mean().item()
            expr_after = (pred[:, 6:] - y_val[:, 6:]).abs().mean().item()
        line = (f"epoch {epoch} train {total / len(x_train):.4f} val {after:.4f} (start {before:.4f}); "
                f"val rotation error {rot_before:.2f} -> {rot_after:.2f} deg, expression MAE {expr_before:.4f} -> {expr_after:.4f}; "
                f"{time.time() - started:.0f} s")
        print(line, flush=True); log.write(line + "\n"); log.flush()
        torch.save({"net": net.state_dict(), "opt": opt.state_dict(), "epoch": epoch}, a.out + ".pt")
    net.eval()

    export(net, a.out + ".onnx")
    with open(a.out + ".columns.txt", "w") as f:
        f.write("\n".join(["d_omega_x", "d_omega_y", "d_omega_z", "d_t_x_over_z", "d_t_y_over_z", "d_t_z_over_z"] + columns[6:]) + "\n")
    print(f"wrote {a.out}.onnx", flush=True)


if __name__ == "__main__":
    main()
