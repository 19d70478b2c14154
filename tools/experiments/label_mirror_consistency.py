#!/usr/bin/python3
"""How far the dense teacher labels of a 300-W crop and of its mirror image disagree (docs/decisions.md, "The CNN cascade").

The dense labels are MediaPipe's mesh fitted with the face model (tools/data/label_dense): another model's
predictions, not ground truth. A photograph and its mirror image show the same head, so their labels should
be mirror images too: R' = M R M with M = diag(-1, 1, 1) (yaw and roll change sign, pitch stays), and each
sided shape's weight moves to its partner. Whatever differs is error of the teacher or of the labeller; of
the two labels at least one is wrong by half the difference or more, so the difference bounds the labels'
own error from below: how often an exact pose could be within 3 deg of them (the pose robustness
measure), and how well any estimate could correlate with their expressions (the r figures of docs/expressions.md).

The teacher reads each crop mirrored in memory (no re-encoding), from a copy of its tool that
`prepare` makes in build/teacher_tool with that one change (the environment variable MIRROR); `prepare`
also writes the mirrored 68 points and index.csv that label_dense reads into build/mirror300w:

  /usr/bin/python3 -m tools.experiments.label_mirror_consistency prepare
  (cd build/teacher_tool && npm ci && MIRROR=1 node label_iris.js images ../../../shared/data/faces300w \
      ../teacher_mirror/faces300w_iris.jsonl --eyelids --mesh ../teacher_mirror/faces300w_mesh.npy)   # ~3 min
  build/tools/label_dense --only 300w --teacher build/teacher_mirror --faces300w build/mirror300w --out build/dense_mirror
  /usr/bin/python3 -m tools.experiments.label_mirror_consistency compare build/dense_labels/faces300w.csv \
      build/dense_mirror/faces300w.csv

`average ORIGINAL MIRRORED OUT` writes the mirror-averaged labels (mirror_averaged below) as a table of
label_dense's columns, for `eval_cnn --tracker --reference OUT`:

  /usr/bin/python3 -m tools.experiments.label_mirror_consistency average build/dense_labels/faces300w.csv \
      build/dense_mirror/faces300w.csv build/dense_averaged/faces300w.csv
"""
import csv, json, os, shutil, sys

import numpy as np

from tools.experiments.label_pose_noise import angle_deg, rotation


# The shapes whose agreement with the labels (r) the expression figures report.
RELIABILITY_SHAPES = ["jawOpen", "mouthSmile_L", "mouthSmile_R", "mouthPucker", "mouthFunnel", "browInnerUp_L",
                      "browInnerUp_R", "browDown_L", "browDown_R"]


def partner(name):
    """The shape's mirror partner (fit::mirrorName's rule): browDown_L and browDown_R, jawLeft and jawRight."""
    for a, b in (("_L", "_R"), ("_R", "_L"), ("Left", "Right"), ("Right", "Left")):
        if name.endswith(a):
            return name[:-len(a)] + b
    return name


REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SHARED = os.path.join(REPO, "..", "shared")

# The mirror image's decoder: the one edit to the teacher's copy.
DECODE = "function decodeImage(file) {\n  const buf = fs.readFileSync(file);"
DECODE_MIRRORED = """function decodeImage(file) {
  const img = decodeImageAsIs(file);
  if (!process.env.MIRROR) return img;
  const { rgb, w, h } = img;
  const out = new Uint8Array(rgb.length);
  for (let y = 0; y < h; y++) for (let x = 0; x < w; x++) for (let c = 0; c < 3; c++) out[(y * w + x) * 3 + c] = rgb[(y * w + (w - 1 - x)) * 3 + c];
  return { rgb: out, w, h };
}

function decodeImageAsIs(file) {
  const buf = fs.readFileSync(file);"""


def prepare():
    from tools.train.refine.train_refine import MIRROR
    tool = os.path.join(REPO, "build", "teacher_tool")
    os.makedirs(tool, exist_ok=True)
    for name in ("package.json", "package-lock.json", "label_iris.js"):
        shutil.copy(os.path.join(SHARED, "tools", "iris-teacher", name), tool)
    script = open(os.path.join(tool, "label_iris.js")).read()
    if DECODE not in script:
        sys.exit("the teacher's label_iris.js has changed: its decodeImage was not found")
    open(os.path.join(tool, "label_iris.js"), "w").write(script.replace(DECODE, DECODE_MIRRORED))
    os.makedirs(os.path.join(REPO, "build", "teacher_mirror"), exist_ok=True)

    faces, out = os.path.join(SHARED, "data", "faces300w"), os.path.join(REPO, "build", "mirror300w")
    widths = {}
    for line in open(os.path.join(SHARED, "data", "teacher", "faces300w_iris.jsonl")):
        record = json.loads(line)
        widths[record["image"]] = record["width"]
    rows = list(csv.DictReader(open(os.path.join(faces, "index.csv"))))
    for row in rows:
        lines = open(os.path.join(faces, row["pts"])).read().split("\n")
        start = lines.index("{")
        points = [tuple(map(float, line.split())) for line in lines[start + 1:start + 69]]
        w = widths[row["image"]]
        flipped = [(w + 1 - points[j][0], points[j][1]) for j in MIRROR]  # iBUG points are 1-based
        os.makedirs(os.path.dirname(os.path.join(out, row["pts"])), exist_ok=True)
        # label_dense finds crops by their image files and reads only their points: a hard link will do (not
        # a symbolic one: std::filesystem::relative would follow it back into ../shared).
        link = os.path.join(out, row["image"])
        if os.path.lexists(link):
            os.remove(link)
        try:
            os.link(os.path.join(faces, row["image"]), link)
        except OSError:
            shutil.copy(os.path.join(faces, row["image"]), link)
        with open(os.path.join(out, row["pts"]), "w") as f:
            f.write("version: 1\nn_points: 68\n{\n" + "".join(f"{x:.3f} {y:.3f}\n" for x, y in flipped) + "}\n")
    shutil.copy(os.path.join(faces, "index.csv"), out)
    print(f"{len(rows)} crops' points mirrored into {out}; the teacher's copy in {tool}")


def consistency(original, mirrored, keys):
    """Per crop in keys, the label (a dict of label_dense's columns) against its mirror image's: the rotation
    angle between M R M and R' (deg); |pitch - pitch'|, |yaw + yaw'|, |roll + roll'|; |w - w'(partner)| per
    shape; and per RELIABILITY_SHAPES name, Pearson r between w and w'(partner) over the crops."""
    names = list(original[keys[0]].keys())
    shapes = names[names.index("id20") + 1:]
    M = np.diag([-1.0, 1.0, 1.0])
    rot, euler, weights = [], [], []
    for k in keys:
        a, b = original[k], mirrored[k]
        Ra = rotation(np.array([float(a["omega_" + c]) for c in "xyz"]))
        Rb = rotation(np.array([float(b["omega_" + c]) for c in "xyz"]))
        rot.append(angle_deg(M @ Ra @ M, Rb))
        euler.append([float(a["pitch_deg"]) - float(b["pitch_deg"]), float(a["yaw_deg"]) + float(b["yaw_deg"]),
                      float(a["roll_deg"]) + float(b["roll_deg"])])
        weights.append([float(a[s]) - float(b[partner(s)]) for s in shapes])
    r = {}
    for name in RELIABILITY_SHAPES:
        x = np.array([float(original[k][name]) for k in keys])
        y = np.array([float(mirrored[k][partner(name)]) for k in keys])
        r[name] = np.corrcoef(x, y)[0, 1] if x.std() > 0 and y.std() > 0 else float("nan")
    return {"shapes": shapes, "rotation": np.array(rot), "euler": np.abs(np.array(euler)),
            "weights": np.abs(np.array(weights)), "r": r}


def axis_angle(R):
    """The angle-axis vector of a rotation matrix (rotation's inverse), for angles below 180 deg."""
    theta = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    if theta < 1e-12:
        return np.zeros(3)
    return theta / (2 * np.sin(theta)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def mirror_averaged(a, b):
    """A crop's label `a` averaged with its mirror image's label `b` mirrored back: the rotation is the rotation
    nearest (R + M R' M) / 2 (the chordal mean), Euler angles (pitch + pitch') / 2, (yaw - yaw') / 2,
    (roll - roll') / 2, each shape's weight (w + w'(partner)) / 2. What mirroring shows of either label's error
    then cancels; an error both share (the teacher's own bias) stays. Translation, identity and the fit's
    residual are the original label's (mirroring them back needs the camera's principal point)."""
    M = np.diag([-1.0, 1.0, 1.0])
    Ra = rotation(np.array([float(a["omega_" + c]) for c in "xyz"]))
    Rb = rotation(np.array([float(b["omega_" + c]) for c in "xyz"]))
    U, _, Vt = np.linalg.svd(Ra + M @ Rb @ M)
    R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    out = dict(a)
    out.update({"omega_" + c: f"{v:.6f}" for c, v in zip("xyz", axis_angle(R))})
    out["pitch_deg"] = f"{(float(a['pitch_deg']) + float(b['pitch_deg'])) / 2:.4f}"
    for angle in ("yaw_deg", "roll_deg"):
        out[angle] = f"{(float(a[angle]) - float(b[angle])) / 2:.4f}"
    names = list(a.keys())
    for s in names[names.index("id20") + 1:]:
        out[s] = f"{(float(a[s]) + float(b[partner(s)])) / 2:.4f}"
    return out


def average(original_csv, mirrored_csv, out_csv):
    original = list(csv.DictReader(open(original_csv)))
    mirrored = {r["key"]: r for r in csv.DictReader(open(mirrored_csv))}
    rows = [mirror_averaged(r, mirrored[r["key"]]) for r in original if r["key"] in mirrored]
    os.makedirs(os.path.dirname(out_csv) or ".", exist_ok=True)
    with open(out_csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(original[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"{len(rows)} of {len(original)} crops' labels averaged with their mirror images' into {out_csv}")


def compare(original_csv, mirrored_csv):
    original = {r["key"]: r for r in csv.DictReader(open(original_csv))}
    mirrored = {r["key"]: r for r in csv.DictReader(open(mirrored_csv))}
    for split in ("train", "validation", "test"):
        keys = [k for k, r in original.items() if r["split"] == split and k in mirrored]
        if not keys:
            continue
        c = consistency(original, mirrored, keys)
        rot, euler, weights, shapes = c["rotation"], c["euler"], c["weights"], c["shapes"]
        print(f"{split}: {len(keys)} crops labelled both ways")
        print(f"  rotation between the label and its mirror image's: mean {rot.mean():.2f}, median {np.median(rot):.2f}, "
              f"p90 {np.percentile(rot, 90):.2f} deg; within 3 deg {100 * (rot <= 3).mean():.0f} %, within 6 deg "
              f"{100 * (rot <= 6).mean():.0f} %")
        # If the two labels' errors are independent and alike, the difference is their error times sqrt 2 (exact
        # for Gaussian errors): a label is within 3 deg of the truth about as often as the pair is within 3 sqrt 2.
        print(f"  so a label is within 3 deg of the true pose on about {100 * (rot <= 3 * np.sqrt(2)).mean():.0f} % of "
              f"crops, counting only the error that mirroring reveals")
        print(f"  |pitch - pitch'|, |yaw + yaw'|, |roll + roll'| mean: {euler.mean(0)[0]:.2f}, {euler.mean(0)[1]:.2f}, "
              f"{euler.mean(0)[2]:.2f} deg")
        order = np.argsort(-weights.mean(0))
        print("  |w - w'(partner)| mean, largest 12 shapes: " +
              ", ".join(f"{shapes[j]} {weights.mean(0)[j]:.3f}" for j in order[:12]))
        print(f"  mean over {len(shapes)} shapes {weights.mean():.3f}")
        # Test-retest: the mirror image's label as a second measurement of the same face. No estimate can
        # correlate with a label better than sqrt of the label's own reliability r (Spearman's bound).
        print("  r between a label and its mirror image's: " +
              ", ".join(f"{n} {r:.2f} (ceiling {np.sqrt(max(r, 0)):.2f})" for n, r in c["r"].items()))


if __name__ == "__main__":
    if len(sys.argv) == 2 and sys.argv[1] == "prepare":
        prepare()
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 5 and sys.argv[1] == "average":
        average(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(__doc__)
