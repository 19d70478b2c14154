#!/usr/bin/env bash
# Command 1 of the README: set up, build, and track.
#   tools/run.sh                        the webcam, else a clip from ../shared/data/clips
#   tools/run.sh my_clip.mp4            a clip (or a folder of images)
#   tools/run.sh --camera /dev/video1   a given camera
# Any 'facetrack track' option works (tools/run.sh --help lists them).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
"$here/setup.sh" >&2
"$here/build.sh" >&2
exec "$here/../${FACETRACK_BUILD_DIR:-build}/tools/facetrack" track "$@"
