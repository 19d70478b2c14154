#!/usr/bin/env bash
# Installs facetrack's build and test dependencies from Debian 12's archive.
# Idempotent: packages already installed are skipped, and apt is not touched
# at all when nothing is missing. Run as root (or with sudo).
set -euo pipefail

packages=(
  # toolchain, and the format check (tools/check_format.sh)
  cmake g++ make pkg-config clang-format
  # libraries the library links
  libeigen3-dev libopencv-dev libopencv-contrib-dev libceres-dev
  # demo: window, GL maths, camera, the side panel (Dear ImGui)
  libglfw3-dev libglm-dev libv4l-dev libgl-dev libgl1-mesa-dri libimgui-dev
  # tools and tests
  nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev
  # detector fallback (Haar cascades) and peers for evaluation (dlib's 68-point model)
  opencv-data libdlib-dev libdlib-data
  # facetrack send: OSC encoding for the VMC protocol
  liboscpack-dev
  # fuzzing (tools/fuzz.sh): clang and its libFuzzer runtime
  clang libclang-rt-14-dev
  # headless rendering for the demo's test, and video decoding
  xvfb xauth ffmpeg
  # CNN training (tools/train/expression, Debian's python3): torch on the CPU, with the threaded
  # OpenBLAS (about 2x the default BLAS on small nets)
  python3-torch python3-numpy libopenblas0-pthread
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} missing packages: ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
