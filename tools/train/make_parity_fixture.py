#!/usr/bin/python3
"""The cv::dnn parity test's fixture (tests/test_cnn_onnx.cpp): a narrow Stage net (train_stage.py's
layers, random weights, seed 3, BatchNorm statistics set so folding matters), exported the same way,
with three standardised inputs and torch's outputs as little-endian float32; and a landmark net of
the same layers whose 136 outputs are constant, every point displaced by (+3, 0) patch pixels
(cnn_landmarks_fixture.onnx, for the stage's landmark geometry); a stage whose update is constant,
no pose change and +0.3 on its one expression (cnn_expression_fixture.onnx, for an expressions-only
cascade); a landmark refiner of train_refine.py's layers on a 32 px patch whose 136 offsets are
constant, every point (+3, 0) patch pixels from the mean shape (refiner_fixture.onnx, for the
refine stage's geometry); the same for the brow and eye refiner of train_region.py, 22 offsets, every
point (+3, 0) (side_fixture.onnx); the gaze stage's iris-net fixture (iris_net_fixture.onnx, below); and a net with a max-pool,
which the own kernels leave to OpenCV's dnn (pooled_fixture.onnx).

  /usr/bin/python3 -m tools.train.make_parity_fixture tests/data
"""
import os, sys

import numpy as np
import torch

from tools.train.expression.train_stage import Stage, export
from tools.train.nets import export_onnx
from tools.train.refine.train_refine import Refiner

out = sys.argv[1] if len(sys.argv) > 1 else "tests/data"
torch.manual_seed(3)


def randomise_batchnorm(net):
    """Statistics that make folding matter (and keep the exporter from merging equal initializers
    into Identity nodes, which OpenCV 4.6 does not load)."""
    for m in net.modules():
        if isinstance(m, torch.nn.BatchNorm2d):
            m.running_mean.uniform_(-0.5, 0.5)
            m.running_var.uniform_(0.5, 2.0)
            m.weight.data.uniform_(0.5, 1.5)
            m.bias.data.uniform_(-0.2, 0.2)


net = Stage(7, widths=(4, 8, 8, 8), hidden=16)
randomise_batchnorm(net)
net.eval()
os.makedirs(out, exist_ok=True)
export(net, os.path.join(out, "cnn_parity.onnx"))
x = torch.randn(3, 1, 64, 64)
with torch.no_grad():
    y = net(x)
x.numpy().astype("<f4").tofile(os.path.join(out, "cnn_parity_input.f32"))
y.numpy().astype("<f4").tofile(os.path.join(out, "cnn_parity_output.f32"))
print(f"wrote {out}/cnn_parity.onnx, inputs 3x1x64x64, outputs {tuple(y.shape)}")

landmarks = Stage(136, widths=(4, 8, 8, 8), hidden=16)
randomise_batchnorm(landmarks)
with torch.no_grad():
    landmarks.head[-1].weight.zero_()
    landmarks.head[-1].bias.copy_(torch.tensor([3.0, 0.0] * 68))
landmarks.eval()
export(landmarks, os.path.join(out, "cnn_landmarks_fixture.onnx"), output="displacement")
print(f"wrote {out}/cnn_landmarks_fixture.onnx")

expression = Stage(7, widths=(4, 8, 8, 8), hidden=16)
randomise_batchnorm(expression)
with torch.no_grad():
    expression.head[-1].weight.zero_()
    expression.head[-1].bias.copy_(torch.tensor([0.0] * 6 + [0.3]))
expression.eval()
export(expression, os.path.join(out, "cnn_expression_fixture.onnx"))
print(f"wrote {out}/cnn_expression_fixture.onnx")

def constant_refiner(points, name):
    """A refiner of train_refine.py's layers on a 32 px patch whose offsets are constant: every point (+3, 0)."""
    net = Refiner(32, widths=(4, 8), strides=(2, 2), hidden=8)
    if points != 68:
        net.head[-1] = torch.nn.Linear(8, 2 * points)
    randomise_batchnorm(net)
    with torch.no_grad():
        net.head[-1].weight.zero_()
        net.head[-1].bias.copy_(torch.tensor([3.0, 0.0] * points))
    export_onnx(net, (1, 1, 32, 32), os.path.join(out, name), "offsets")
    print(f"wrote {out}/{name}")


constant_refiner(68, "refiner_fixture.onnx")
constant_refiner(11, "side_fixture.onnx")

# The gaze stage's iris-net fixture (tests/test_gaze.cpp): 2 x 1 x 28 x 40 -> 2 x 3 x 14 x 20 like
# tools/train/eyes/train_iris_net.py's nets, but each cell's scores come from its own patch pixel
# (2i, 2j) alone, (0, 0, 4 v): P(iris) = e^(4v) / (2 + e^(4v)), so the test can check the grid.
iris = torch.nn.Sequential(torch.nn.Conv2d(1, 3, 1, stride=2), torch.nn.Softmax(dim=1))
with torch.no_grad():
    iris[0].weight.copy_(torch.tensor([0.0, 0.0, 4.0]).view(3, 1, 1, 1))
    iris[0].bias.zero_()
export_onnx(iris, (1, 1, 28, 40), os.path.join(out, "iris_net_fixture.onnx"), "classes")
print(f"wrote {out}/iris_net_fixture.onnx")

# A net the own kernels do not run (core/conv_chain.hpp: a max-pool between its convolution and its dense
# layer): OnnxNet must run it with OpenCV's dnn instead (tests/test_cnn_onnx.cpp).
pooled = torch.nn.Sequential(torch.nn.Conv2d(1, 4, 3, padding=1), torch.nn.ReLU(), torch.nn.MaxPool2d(2), torch.nn.Flatten(),
                             torch.nn.Linear(4 * 8 * 8, 5))
export_onnx(pooled, (1, 1, 16, 16), os.path.join(out, "pooled_fixture.onnx"), "values")
print(f"wrote {out}/pooled_fixture.onnx")

# A stage that reads a patch's sides unequally (mirror_fixture.onnx, for a mirror-averaged cascade): no
# pose change, its first expression 0.3 + 0.1 L with L the standardised patch's mean over its left half
# (columns 0-31), its second 0. Read with the patch flipped and mirrored back, the two average to
# 0.15 + 0.05 L and 0.15 - 0.05 L.
mirror = torch.nn.Sequential(torch.nn.Conv2d(1, 1, 1), torch.nn.Flatten(), torch.nn.Linear(64 * 64, 8))
with torch.no_grad():
    mirror[0].weight.fill_(1.0)
    mirror[0].bias.zero_()
    mirror[2].weight.zero_()
    mirror[2].bias.copy_(torch.tensor([0.0] * 6 + [0.3, 0.0]))
    mirror[2].weight[6].view(64, 64)[:, :32] = 0.1 / (64 * 32)
export_onnx(mirror, (1, 1, 64, 64), os.path.join(out, "mirror_fixture.onnx"), "update")
print(f"wrote {out}/mirror_fixture.onnx")

# The lip net's geometry (tests/test_lip_net.cpp): a face's 68 points (a grid with the eyes apart, rolled
# by 0.2 rad) and the mouth patch map train_lips.py cuts for them, "A00 A01 t0 A10 A11 t1"
# (mouth_patch_fixture.txt); and a lip net of batch 2 whose 80 outputs are constant, every point at
# (+0.25, +0.5) (lip_fixture.onnx): read with its mirror image, x averages to 0.
from tools.train.expression.train_lips import patch_map, SIZE
rng = np.random.default_rng(5)
face = np.stack([200 + 3.0 * (np.arange(68) % 17), 150 + 2.0 * (np.arange(68) // 17)], 1) + rng.uniform(-4, 4, (68, 2))
face[36:42] = [170, 140] + rng.uniform(-4, 4, (6, 2))
face[42:48] = [230, 140] + rng.uniform(-4, 4, (6, 2))
roll = np.array([[np.cos(0.2), -np.sin(0.2)], [np.sin(0.2), np.cos(0.2)]])
face = face @ roll.T
A, t, _ = patch_map(face)
with open(os.path.join(out, "mouth_patch_fixture.txt"), "w") as f:
    f.write(" ".join(f"{v:.9g}" for v in face.reshape(-1)) + "\n")
    f.write(" ".join(f"{v:.9g}" for v in (A[0, 0], A[0, 1], t[0], A[1, 0], A[1, 1], t[1])) + "\n")
print(f"wrote {out}/mouth_patch_fixture.txt")
lips = torch.nn.Sequential(*[layer for k in range(4) for layer in (torch.nn.Conv2d(1, 1, 3, 2, 1), torch.nn.ReLU())],
                           torch.nn.Flatten(), torch.nn.Linear((SIZE // 16) ** 2, 80))
with torch.no_grad():
    for k, conv in enumerate(m for m in lips if isinstance(m, torch.nn.Conv2d)):
        conv.weight.fill_(0.01 * (k + 1))  # distinct, or the exporter merges them into nodes OpenCV does not load
        conv.bias.fill_(0.1 * (k + 1))
    lips[-1].weight.zero_()
    lips[-1].bias.copy_(torch.tensor([0.25, 0.5] * 40))
export_onnx(lips, (2, 1, SIZE, SIZE), os.path.join(out, "lip_fixture.onnx"), "lips")
print(f"wrote {out}/lip_fixture.onnx")
