#!/usr/bin/python3
"""Which of the fit's shapes an expressions-only stage should correct (docs/decisions.md, "The fit"): on the
300-W validation crops' unperturbed samples (make_cnn_samples --starts-from fit: the start is the fit's own
answer), per shape, the fit's value and the corrected one (start + the net's update, mirror-averaged as the
stage runs it, clamped to [0, 1]) against the dense teacher labels (MediaPipe's mesh fitted with the face
model: teacher labels, not ground truth): Pearson r, the rest level (train_stage.py's: the 0.9 quantile over
the crops whose label is at most its median) and the response (the mean over the top quarter by label minus
the mean at rest). The rule: correct a shape the fit estimates where the corrected estimate agrees better and
reads no higher at rest, a mirror pair's values averaged (the eyes' shapes are the gaze stage's: left out).

  /usr/bin/python3 -m tools.experiments.fit_corrections build/cnn_samples_moved build/cnn/expr36m.best.pt
"""
import os, sys

import numpy as np
import torch

from tools.experiments.label_mirror_consistency import partner
from tools.train.expression import train_stage


def pearson(a, b):
    a, b = a - a.mean(), b - b.mean()
    d = (a.norm() * b.norm()).item()
    return (a @ b).item() / d if d > 1e-9 else float("nan")


def figures(estimate, label):
    at_rest = label <= label.median()
    top = label >= label.quantile(0.75)
    rest = estimate[at_rest].quantile(train_stage.REST_QUANTILE).item()
    return pearson(estimate, label), rest, (estimate[top].mean() - estimate[at_rest].mean()).item()


def chosen(table):
    """The rule over table[name] = ((r, rest, response) of the fit, the same corrected): the shapes whose
    corrected estimate agrees better (r) and reads no higher at rest, each mirror pair's values averaged."""
    out = []
    for n in table:
        pair = [m for m in (n, partner(n)) if m in table]
        mean = lambda which, field: np.mean([table[m][which][field] for m in pair])  # noqa: E731
        if mean(1, 0) > mean(0, 0) and mean(1, 1) <= mean(0, 1):
            out.append(n)
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    samples, checkpoint = sys.argv[1], sys.argv[2]
    torch.set_num_threads(2)
    header, rows = train_stage.read_csv(os.path.join(samples, "faces300w_samples.csv"))
    first = header.index("d_omega_x")
    keep = [i for i, r in enumerate(rows) if r[1] == "validation" and r[2] == "0"]
    patches = np.load(os.path.join(samples, "faces300w_patches.npy"), mmap_mode="r")
    x = train_stage.standardise(torch.as_tensor(np.asarray(patches[keep])))
    columns = [c[2:] for c in header[first:]]
    names = columns[6:]
    update = torch.tensor([[float(v) for v in rows[i][first:]] for i in keep])
    labels = torch.tensor([[float(rows[i][header.index("label_" + n)]) for n in names] for i in keep])
    start = labels - update[:, 6:]
    state = torch.load(checkpoint)
    net = train_stage.Stage(len(columns), state["widths"], state["hidden"], state.get("dropout", 0.0))
    net.load_state_dict(state["net"])
    net.eval()
    order, sign = train_stage.mirror_permutation(columns)
    back = torch.empty_like(order)
    back[order] = torch.arange(len(order))
    with torch.no_grad():  # the patch and its mirror image, the latter's update mirrored back (cnn/update_net.hpp)
        pred = 0.5 * (net(x) * state["scale"] + (net(x.flip(3)) * state["scale"] * sign)[:, back])
    corrected = (start + pred[:, 6:]).clamp(0, 1)
    print(f"{len(keep)} validation crops (teacher labels, not ground truth)")
    print(f"{'shape':18s} {'r: fit / corrected':>20s} {'rest: fit / corrected':>24s} {'response: fit / corrected / label':>36s}")
    table = {}
    for k, n in enumerate(names):
        if start[:, k].std() < 1e-6 or n.startswith("eye"):
            continue  # a shape the fit does not estimate (the eyes' are the gaze stage's)
        table[n] = (figures(start[:, k], labels[:, k]), figures(corrected[:, k], labels[:, k]))
        (rf, qf, sf), (rc, qc, sc) = table[n]
        lr = figures(labels[:, k], labels[:, k])[2]
        print(f"{n:18s} {rf:+9.2f} / {rc:+.2f} {qf:15.3f} / {qc:.3f} {sf:+20.3f} / {sc:+.3f} / {lr:+.3f}")
    print("the rule corrects: " + " ".join(chosen(table)))


if __name__ == "__main__":
    main()
