#!/usr/bin/env bash
# Retrains every model of models/ from ../shared, into build/retrain/models/ (models/ itself is not
# touched: a retrained model is committed only when it improves the measured figures).
#
#   tools/train/retrain_all.sh            run, or resume after the last finished step
#   tools/train/retrain_all.sh --list     the steps, their measured times, and which are done
#   tools/train/retrain_all.sh --from N   run again from step N
#   tools/train/retrain_all.sh --only N   run step N alone
#
# Each step's output goes to build/retrain/<step>.log; a finished step leaves build/retrain/<step>.done,
# so a second run (after a reboot, a kill) skips it. 3 h 28 min on the 2-core development
# machine, end to end (each step's time: tools/README.md). Run it in the background:
#   nohup tools/train/retrain_all.sh > build/retrain.out 2>&1 &
set -euo pipefail
cd "$(dirname "$0")/../.."
out=build/retrain
models=$out/models
mkdir -p "$out" "$models"
py=(/usr/bin/python3 -m)
bin=build/tools

steps=(
  "face_model        1 s   build/tools/convert_face_model (deterministic: the shipped file again)"
  "dense_labels    18 min  MediaPipe's mesh fitted with the face model (teacher labels, not ground truth)"
  "landmarks       18 min  the LBF regressor on the 300-W training split"
  "convention       4 min  the fit's landmark convention and expression prior"
  "eyes            27 min  the eye model's forests, corner cascade and iris CNN"
  "refine_data     10 min  LBF's points on 300-W, face-profiled copies, the crops as arrays"
  "refine          55 min  the landmark refiner"
  "sides           23 min  the brow and eye refiner per side"
  "expression      53 min  the expression stage's samples (teacher, warped faces), texture and geometry nets, packed into the CNN file"
)

done_file() { echo "$out/$1.done"; }

run_step() {
  local name=$1
  case $name in
    face_model)
      $bin/convert_face_model --source ../shared/models/ict-facekit/FaceXModel --out $models/face_model.ftm ;;
    dense_labels)
      $bin/label_dense --out build/dense_labels ;;
    landmarks)
      $bin/train_landmarks --out $models/landmarks_lbf.ftm --ridge 20000 --trees 4 --depth 5 --stages 10 --inits 16 ;;
    convention)
      $bin/train_convention --out $models/landmark_convention.ftm --dense-labels build/dense_labels ;;
    eyes)
      $bin/train_eyes --out $models/eye_model.ftm
      $bin/train_eyes --samples-out build/eye_samples
      "${py[@]}" tools.train.eyes.train_iris_net --width 8 --synthetic-share 0 --minutes 15 --threads 1 --out build/eyes/iris_w8_s0
      $bin/train_eyes --from $models/eye_model.ftm --iris-net build/eyes/iris_w8_s0.onnx --out $models/eye_model.ftm ;;
    refine_data)
      mkdir -p build/refine build/region
      for s in train validation test; do
        FACETRACK_MODEL_DIR=$models $bin/facetrack eval-landmarks ../shared/data/faces300w --split $s --lbf-only --landmark-starts 5 --dlib none \
          --points-out build/refine/points_$s.csv
        $bin/make_profiled_faces --split $s --out build/profiled/$s --copies 10
      done
      for s in train validation; do
        FACETRACK_MODEL_DIR=$models $bin/facetrack eval-landmarks build/profiled/$s --lbf-only --landmark-starts 5 --dlib none --points-out build/profiled/points_$s.csv
        "${py[@]}" tools.train.refine.load_faces build/profiled/$s build/profiled/$s/faces.npz
      done
      "${py[@]}" tools.train.refine.load_faces ../shared/data/faces300w build/refine/faces.npz ;;
    refine)
      "${py[@]}" tools.train.refine.train_refine --minutes 55 --profiled build/profiled --out build/refine/lp
      "${py[@]}" tools.train.refine.train_refine --out build/refine/lp --profiled build/profiled --export --evaluate validation
      $bin/pack_refiner --refiner build/refine/lp.onnx --out $models/landmark_refiner.ftm --provenance "tools/train/retrain_all.sh: refiner" ;;
    sides)
      # The pipeline's points with the new refiner, then the side net trained on them.
      for s in train validation test; do
        FACETRACK_MODEL_DIR=$models $bin/facetrack eval-landmarks ../shared/data/faces300w --split $s --refiner $models/landmark_refiner.ftm --dlib none \
          --points-out build/region/points_$s.csv
      done
      for s in train validation; do
        FACETRACK_MODEL_DIR=$models $bin/facetrack eval-landmarks build/profiled/$s --refiner $models/landmark_refiner.ftm --dlib none \
          --points-out build/region/profiled_points_$s.csv
      done
      local net=(--out build/region/c8 --widths 8,16,32,64 --strides 2,2,2,2 --hidden 128 --profiled build/profiled)
      "${py[@]}" tools.train.refine.train_region "${net[@]}" --minutes 20
      "${py[@]}" tools.train.refine.train_region "${net[@]}" --evaluate validation --brows-only --export
      $bin/pack_refiner --base $models/landmark_refiner.ftm --sides build/region/c8.onnx --out $models/landmark_refiner.ftm \
        --provenance "tools/train/retrain_all.sh: refiner, sides" ;;
    expression)  # its intermediate files under build/retrain, beside (not over) a manual run's in build/
      mkdir -p $out/tracked $out/cnn
      FACETRACK_MODEL_DIR=$models $bin/make_cnn_samples --starts-from fit --max-start-deg 25 --perturb 6 --clip-perturb 3 --rotation-deg 5 --yaw-deg 6 \
        --translation 0.02 --depth 0.04 --expression-sigma 0.05 --tracked-clips --expression-copies 6 --clip-copies 3 \
        --clip-copy-every 6 --arkit ../shared/data/arkit --arkit-every 4 --out $out/cnn_samples
      "${py[@]}" tools.train.expression.train_stage --samples $out/cnn_samples --out $out/cnn/v2 --expressions \
        --teacher ../shared/data/teacher --copies-per-epoch 2 --clips-per-epoch 1.5 --dropout 0.3 --minutes 45
      # the geometry net reads the landmarks as the retrained pipeline tracks every clip (the trainer reads the splits)
      for clip in ../shared/data/clips/*.mp4; do
        FACETRACK_MODEL_DIR=$models $bin/facetrack track "$clip" --raw --profile none \
          --out "$out/tracked/$(basename "$clip" .mp4).jsonl" 2>/dev/null
      done
      for split in train validation; do
        FACETRACK_MODEL_DIR=$models tools/data/track_faces300w.sh $split $out/tracked_300w
      done
      "${py[@]}" tools.train.expression.train_geometry --tracked $out/tracked --tracked-crops $out/tracked_300w \
        --net $out/cnn/v2 --out $out/cnn/geometry
      $bin/pack_cnn --nets $out/cnn/v2.onnx --expressions-only --rest-from-validation \
        --gain-from-validation --mirror-average --min-validation-r 0.1 --leave-out cheekSquint_L,cheekSquint_R,noseSneer_L,noseSneer_R \
        --corrects-fit --geometry $out/cnn/geometry --out $models/cnn_cascade.ftm \
        --provenance "tools/train/retrain_all.sh: expressions" ;;
    *) echo "retrain_all: no step '$name'" >&2; return 2 ;;
  esac
}

from=1
only=0
case "${1:-}" in
  --list)
    i=1
    for s in "${steps[@]}"; do
      name=${s%% *}
      [ -f "$(done_file "$name")" ] && state="done" || state="to do"
      printf '%2d  %-6s %s\n' $i "$state" "$s"
      i=$((i + 1))
    done
    exit 0 ;;
  --from) from=${2:?--from needs a step number} ;;
  --only) only=${2:?--only needs a step number} ;;
  "") ;;
  *) sed -n '2,13p' "$0"; exit 2 ;;
esac

[ -x $bin/facetrack ] || { echo "retrain_all: build first (tools/build.sh)" >&2; exit 1; }
[ -d ../shared/data ] || { echo "retrain_all: ../shared is missing: the training data lives there" >&2; exit 1; }

i=1
for s in "${steps[@]}"; do
  name=${s%% *}
  if [ "$only" -gt 0 ] && [ $i -ne "$only" ]; then
    :
  elif [ "$only" -eq 0 ] && { [ $i -lt "$from" ] || { [ "$from" -eq 1 ] && [ -f "$(done_file "$name")" ]; }; }; then
    echo "retrain_all: [$i/${#steps[@]}] $name: skipped ($( [ -f "$(done_file "$name")" ] && echo "done in $(cat "$(done_file "$name")")" || echo "before --from"))"
  else
    rm -f "$(done_file "$name")"
    echo "retrain_all: [$i/${#steps[@]}] $s ($(date +%H:%M), log $out/$name.log)"
    start=$(date +%s)
    if ! run_step "$name" > "$out/$name.log" 2>&1; then
      echo "retrain_all: step $name failed; see $out/$name.log, then run again to resume here" >&2
      exit 1
    fi
    echo "$(( $(date +%s) - start )) s" > "$(done_file "$name")"
    echo "retrain_all: [$i/${#steps[@]}] $name took $(cat "$(done_file "$name")")"
  fi
  i=$((i + 1))
done
echo "retrain_all: every model is in $models; measure it (docs/benchmarks.md) before it replaces one in models/"
