#!/usr/bin/env bash
# README command 2: install what is missing, build, and run the tests: an optimised build with
# warnings as errors and every test (the commands end to end and the benchmarks' quick runs
# included), then the ASan+UBSan build of the layers and their tests; then each parser's
# libFuzzer target for 10 s (fuzz/run.sh, clang). `--quick` skips the sanitizer and fuzz passes.
# What each pass checks and why: docs/CI.md.
# Prints each step's wall time at the end (CI's budget: docs/CI.md).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"
# The compiler cache (ccache, when installed: scripts/setup.sh installs it) keys on paths relative
# to the clone and ignores the working folder, so a clone elsewhere on a reused machine hits.
export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
step_names=()
step_secs=()
timed() {
  local name="$1"
  shift
  local start=$SECONDS
  "$@"
  step_names+=("$name")
  step_secs+=($((SECONDS - start)))
}
report() {
  local total=0 i
  echo "== step times" >&2
  for i in "${!step_names[@]}"; do
    printf '   %-28s %6d s\n' "${step_names[$i]}" "${step_secs[$i]}" >&2
    total=$((total + step_secs[i]))
  done
  printf '   %-28s %6d s\n' "total" "$total" >&2
}
trap report EXIT
configure_and_build() {
  local preset="$1"
  [ -f "build/${preset}/build.ninja" ] || cmake --preset "${preset}" >/dev/null
  cmake --build --preset "${preset}" -j"${jobs}"
}
timed "setup (apt)" scripts/setup.sh
# OpenCV's chessboard photographs for the calibration test on real images (best effort: the
# test skips with a message where apt cannot fetch them).
fetch_photos() {
  local dir
  dir="$(scripts/fetch-test-photos.sh || true)"
  if [ -n "$dir" ]; then export PS_OPENCV_SAMPLES="$dir"; fi
}
timed "test photographs" fetch_photos
for preset in release asan; do
  [ "$preset" = asan ] && [ "${1:-}" = "--quick" ] && break
  echo "== ${preset}: configure and build" >&2
  timed "${preset}: build" configure_and_build "$preset"
  echo "== ${preset}: tests" >&2
  timed "${preset}: tests" ctest --preset "${preset}" -j"${jobs}"
done
if [ "${1:-}" != "--quick" ]; then
  echo "== fuzz: every parser, 10 s each" >&2
  timed "fuzz: build and run" fuzz/run.sh 10
fi
echo "== all tests passed" >&2
