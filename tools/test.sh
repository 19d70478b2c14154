#!/usr/bin/env bash
# Command 2 of the README: set up, build with warnings as errors, run every test.
# Tests that need ../shared skip with a message when it is absent.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
"$here/setup.sh"
"$here/build.sh"
cd "$here/../${FACETRACK_BUILD_DIR:-build}"
ctest --output-on-failure -j"$(nproc)" "$@"
