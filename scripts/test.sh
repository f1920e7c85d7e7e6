#!/usr/bin/env bash
# README command 2: install what is missing, build, and run every test twice: an optimised
# build with warnings as errors, then the ASan+UBSan build; then each parser's libFuzzer target
# for 20 s (fuzz/run.sh, clang). `--quick` skips the sanitizer and fuzz passes.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
jobs="$(nproc)"
run_preset() {
  local preset="$1"
  echo "== ${preset}: configure and build" >&2
  [ -f "build/${preset}/build.ninja" ] || cmake --preset "${preset}" >/dev/null
  cmake --build --preset "${preset}" -j"${jobs}"
  echo "== ${preset}: tests" >&2
  ctest --preset "${preset}" -j"${jobs}"
}
run_preset release
if [ "${1:-}" != "--quick" ]; then
  run_preset asan
  echo "== fuzz: every parser, 20 s each" >&2
  fuzz/run.sh 20
fi
echo "== all tests passed" >&2
