#!/usr/bin/env bash
# The 300-W crops of a split as the pipeline tracks a still photo: `facetrack track --raw` on each
# (the tracker starts afresh on every image of a folder), for the geometry net's trainer
# (tools/train/expression/train_geometry.py --tracked-crops).
#
#   tools/data/track_faces300w.sh SPLIT OUT_DIR      (SPLIT: train or validation)
#
# Writes OUT_DIR/SPLIT.txt (the crops' keys, ../shared/data/faces300w-relative, one a line) and
# OUT_DIR/SPLIT.jsonl (one result line per crop, in the same order). The split is the one every
# tool uses (facetrack eval-landmarks --split).
set -euo pipefail
cd "$(dirname "$0")/../.."
split=${1:?usage: track_faces300w.sh SPLIT OUT_DIR}
out=${2:?usage: track_faces300w.sh SPLIT OUT_DIR}
faces=$(realpath ../shared/data/faces300w)
mkdir -p "$out"
links=$(mktemp -d)
trap 'rm -rf "$links"' EXIT
build/tools/facetrack eval-landmarks "$faces" --split "$split" --dlib none --points-out "$links/points.csv" > /dev/null
# the crops in the order eval-landmarks read them; linked as 00000.jpg, 00001.jpg, ... so that the
# tracker, which reads a folder sorted by name, keeps that order
grep ',"annotation",' "$links/points.csv" | cut -d, -f1 | tr -d '"' | sed "s|^$faces/||" > "$out/$split.txt"
mkdir "$links/crops"
n=0
while read -r key; do
  ln -s "$faces/$key" "$links/crops/$(printf '%05d' $n).${key##*.}"
  n=$((n + 1))
done < "$out/$split.txt"
build/tools/facetrack track "$links/crops" --raw --profile none --out "$out/$split.jsonl" 2> /dev/null
lines=$(wc -l < "$out/$split.jsonl")
[ "$lines" -eq "$n" ] || { echo "track_faces300w: $lines results for $n crops" >&2; exit 1; }
echo "track_faces300w: $n $split crops -> $out/$split.jsonl"
