#!/usr/bin/env bash
# MediaPipe Face Landmarker's 478 points for every 300-W crop and every clip frame, for the lip
# net's trainer (tools/train/expression/train_lips.py): the model whose blendshapes the expression
# stage learns from, so its lips are the points those blendshapes are read from. Teacher labels:
# another model's predictions, not ground truth.
#
#   tools/data/label_teacher_mesh.sh OUT_DIR
#
# Runs ../shared/tools/blendshape-teacher (headless Chromium, offline once `npm ci` has run; about
# 7 min on two cores) from a copy in OUT_DIR, as ../shared is read-only. Installs Debian's chromium
# when it is missing (training only: CI does not need it). Writes OUT_DIR/{faces300w,clips}.csv
# (the blendshapes, as ../shared/data/teacher has them) and OUT_DIR/{faces300w,clips}_mesh.npy
# (float32, rows x 478 x 3, row i = CSV data row i; x, y in pixels with 0 at the image's left edge).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:?usage: label_teacher_mesh.sh OUT_DIR}
shared=$(realpath ../shared)
if ! command -v chromium > /dev/null; then
  echo "label_teacher_mesh: installing Debian's chromium" >&2
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends chromium
fi
# the tool serves its page and the model from the folder two above it
mkdir -p "$out/teacher/tools" "$out/teacher/models"
rm -rf "$out/teacher/tools/blendshape-teacher"
cp -r "$shared/tools/blendshape-teacher" "$out/teacher/tools/"
chmod -R u+w "$out/teacher/tools/blendshape-teacher"
ln -sfn "$shared/models/mediapipe-face-landmarker" "$out/teacher/models/mediapipe-face-landmarker"
(cd "$out/teacher/tools/blendshape-teacher" && npm ci --no-audit --no-fund > /dev/null)
label=$out/teacher/tools/blendshape-teacher/label.py
/usr/bin/python3 "$label" images "$shared/data/faces300w" "$out/faces300w.csv" --mesh "$out/faces300w_mesh.npy"
/usr/bin/python3 "$label" clips "$shared/data/clips" "$out/clips.csv" --mesh "$out/clips_mesh.npy"
echo "label_teacher_mesh: wrote $out/{faces300w,clips}.csv and _mesh.npy"
