#!/usr/bin/env bash
# Makes the seed corpora in fuzz/corpus/ (committed: small, and made only from
# facetrack's own models and renders). Run from the repository root after
# tools/build.sh; it overwrites the seeds.
set -euo pipefail
cd "$(dirname "$0")/.."
corpus=fuzz/corpus
# Inputs that once crashed (regression-*) stay.
mkdir -p "$corpus/fuzz_model_files" "$corpus/fuzz_tracker" "$corpus/fuzz_handshake" "$corpus/fuzz_c_api"
find "$corpus" -type f ! -name 'regression-*' -delete

# Model files: per loader (the order of fuzz_model_files.cpp's kFormats), the
# file's first 256 bytes as a whole file, and its payload's first 2 KB to be
# wrapped in a valid container (selector's top bit).
formats=(face_model.ftm landmarks_lbf.ftm eye_model.ftm landmark_convention.ftm cnn_cascade.ftm landmark_refiner.ftm)
for k in "${!formats[@]}"; do
  f=models/${formats[$k]}
  { printf "\\x$(printf %02x "$k")"; head -c 256 "$f"; } > "$corpus/fuzz_model_files/raw_$k"
  { printf "\\x$(printf %02x $((k | 128)))"; dd if="$f" bs=32 skip=1 count=64 status=none; } > "$corpus/fuzz_model_files/payload_$k"
done

# Frames: a 10-byte header (fuzz_tracker.cpp), then pixels.
frame() {  # name width height format padding flags file
  local name=$1 w=$2 h=$3 fmt=$4 pad=$5 flags=$6 pixels=$7
  { printf "\\x$(printf %02x $((w & 255)))\\x$(printf %02x $((w >> 8)))\\x$(printf %02x $((h & 255)))\\x$(printf %02x $((h >> 8)))"
    printf "\\x$(printf %02x "$fmt")\\x$(printf %02x "$pad")\\x21\\x00\\x$(printf %02x "$flags")\\x50"
    cat "$pixels"; } > "$corpus/fuzz_tracker/$name"
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# A render of the face model (eval-gaze's first synthetic render), grey 160 x 120.
(cd "$tmp" && "$OLDPWD/build/tools/facetrack" eval-gaze --clips "" --split none --synthetic 1 > /dev/null 2>&1)
ffmpeg -loglevel error -i "$tmp/synthetic_gaze_0.png" -vf scale=160:120 -pix_fmt gray -f rawvideo "$tmp/face_gray.raw"
ffmpeg -loglevel error -i "$tmp/synthetic_gaze_0.png" -vf scale=96:72 -pix_fmt bgr24 -f rawvideo "$tmp/face_bgr.raw"
head -c 3072 /dev/urandom > "$tmp/noise.raw"
frame face_gray 160 120 0 0 0 "$tmp/face_gray.raw"
frame face_bgr_box 96 72 1 0 8 "$tmp/face_bgr.raw"
frame face_gray_cnn 160 120 0 0 16 "$tmp/face_gray.raw"      # the tracker with the cnn stage
frame face_bgr_box_cnn 96 72 1 0 24 "$tmp/face_bgr.raw"
frame noise_rgba 32 24 4 0 0 "$tmp/noise.raw"
frame odd_stride 7 5 2 3 2 "$tmp/noise.raw"
frame short_stride 8 8 0 255 1 "$tmp/noise.raw"
frame empty 0 0 0 0 4 /dev/null

# C API calls: a 32-byte header (fuzz_c_api.cpp), then pixels: frames as above,
# a face read back, a neutral calibrated, a tracker from a configuration, an
# older caller's smaller ft_frame_result.
capi() {  # name call struct_offset width height format face_index config(8 comma-separated) file
  /usr/bin/python3 -c '
import struct, sys
name, call, offset, w, h, fmt, index, config, pixels = sys.argv[1:]
header = struct.pack("<BBhiihbbd", int(call), 0, int(offset), int(w), int(h), 0, int(fmt), int(index), 1 / 30)
header += bytes(int(c) for c in config.split(","))
sys.stdout.buffer.write(header + open(pixels, "rb").read())' "$@" > "$corpus/fuzz_c_api/$1"
}
defaults=1,5,30,60,0,1,10,30
capi face_gray 0 0 160 120 0 0 $defaults "$tmp/face_gray.raw"
capi face_bgr 0 0 96 72 1 0 $defaults "$tmp/face_bgr.raw"
capi older_result 0 -8 160 120 0 0 $defaults "$tmp/face_gray.raw"
capi face_read 1 0 0 0 0 0 $defaults /dev/null
capi calibrate_neutral 4 0 0 0 0 0 $defaults /dev/null
capi estimated 6 0 0 0 0 0 $defaults /dev/null
capi create_and_process 7 0 160 120 0 0 $defaults "$tmp/face_gray.raw"
capi create_older_config 7 -12 96 72 1 0 2,1,0,90,60,0,5,20 "$tmp/face_bgr.raw"
printf '{"format": "facetrack-calibration", "version": 1, "shapes": {"jawOpen": {"neutral": 0.05, "full": 0.6, "gain": 1.5, "dead_zone": 0.1}}, "native_neutral": [], "identity": []}' > "$tmp/profile.json"
capi calibration_json 8 0 0 0 0 0 $defaults "$tmp/profile.json"
/usr/bin/python3 -c 'import struct, sys
sys.stdout.buffer.write(struct.pack("<BBhiihbb4f", 9, 0, 0, 0, 0, 0, 0, 17, 0.05, 0.6, 1.5, 0.1))' > "$corpus/fuzz_c_api/shape_calibration"

# Datagrams: the two handshakes and a near miss.
printf 'iFacialMocap_sahuasouryya9218sauhuiayeta91555dy3719' > "$corpus/fuzz_handshake/v1"
printf 'iFacialMocap_sahuasouryya9218sauhuiayeta91555dy3719|sendDataVersion=v2\n' > "$corpus/fuzz_handshake/v2"
printf 'iFacialMocap_sahuasouryya9218sauhuiayeta91555dy3719|sendDataVersion=v3' > "$corpus/fuzz_handshake/v3"
du -sh "$corpus"
