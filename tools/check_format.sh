#!/usr/bin/env bash
# The C and C++ sources against .clang-format: lists the files that differ and
# exits 1. With --fix, formats them in place.
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h' '*.c' 2>/dev/null || find libfacetrack tools tests benchmarks demo fuzz -name '*.[ch]pp' -o -name '*.[ch]')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  echo "check_format: formatted ${#files[@]} files"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  printf 'check_format: not formatted: %s\n' "${bad[@]}" >&2
  echo "check_format: ${#bad[@]} of ${#files[@]} files differ from .clang-format (tools/check_format.sh --fix)" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files as .clang-format says"
