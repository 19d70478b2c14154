#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, ASan and UBSan in their own
# build directory (build-fuzz) and runs each for a bounded time, from its seed
# corpus in fuzz/corpus/ (read only) plus what earlier runs found
# (build-fuzz/corpus/, where new inputs go). A crash leaves its input in
# build-fuzz/ (crash-*, leak-*, timeout-*) and fails the script.
#   tools/fuzz.sh          # 40 s per target (CI: four targets, under 3 minutes)
#   tools/fuzz.sh 3600     # an hour per target
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
seconds=${1:-40}
"$here/setup.sh"
cd "$here/.."
export CC=clang CXX=clang++
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFACETRACK_WERROR=ON -DFACETRACK_FUZZ=ON \
    -DFACETRACK_BUILD_TESTS=OFF -DFACETRACK_BUILD_BENCHMARKS=OFF -DFACETRACK_BUILD_DEMO=OFF
fi
targets=(fuzz_model_files fuzz_tracker fuzz_c_api fuzz_handshake)
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$here/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
for t in "${targets[@]}"; do
  mkdir -p "build-fuzz/corpus/$t"
  echo "fuzz: $t for $seconds s"
  (cd build-fuzz && "./fuzz/$t" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -print_final_stats=1 \
     "corpus/$t" "../fuzz/corpus/$t" > "fuzz-$t.log" 2>&1) || { tail -60 "build-fuzz/fuzz-$t.log"; echo "fuzz: $t found a problem"; exit 1; }
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "build-fuzz/fuzz-$t.log" | sed "s/^/fuzz: $t /"
done
