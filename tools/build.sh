#!/usr/bin/env bash
# Configures (once) and builds facetrack in ./build. Extra arguments go to the
# first cmake configure, e.g. tools/build.sh -DFACETRACK_BUILD_BENCHMARKS=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${FACETRACK_BUILD_DIR:-build}
if [ ! -f "$build/CMakeCache.txt" ] || [ $# -gt 0 ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DFACETRACK_WERROR=ON "$@"
fi
cmake --build "$build" -j"$(nproc)"
