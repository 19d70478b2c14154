#!/usr/bin/env bash
# The tests again, built with AddressSanitizer and UndefinedBehaviorSanitizer
# in their own build directory (build-asan). The demo (the GL driver is not
# ours), the benchmarks (timing under ASan means nothing) and the model tools
# (no test runs them; the Release build compiles them) are left out.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
"$here/setup.sh"
export FACETRACK_BUILD_DIR=build-asan
"$here/build.sh" -DFACETRACK_SANITIZE=ON -DFACETRACK_BUILD_BENCHMARKS=OFF -DFACETRACK_BUILD_DEMO=OFF -DFACETRACK_BUILD_MODEL_TOOLS=OFF \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG"  # line tables: enough for ASan's reports, faster to build
cd "$here/../build-asan"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$here/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
# Left out here (they run in the Release build): the CLI option sweep and the
# slowest numerical evaluations, which spend minutes under ASan in code the
# other tests and the fuzz targets already cover (CI's 45-minute budget).
ctest --output-on-failure -j"$(nproc)" \
  -E '^(Cli/EveryOption\.|Cli\.EvalGazeSeparatesTheFitsErrorFromTheGeometrysOnRenders$|DenseCorrespondence\.CanonicalMeshLiesOnTheModelAndFitsNoExpression$|DenseObservability\.)' "$@"
