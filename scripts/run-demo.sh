#!/usr/bin/env bash
# README command 1: install what is missing, build, and run the main job on the bundled default.
# Extra arguments go to `planetsculpt demo` (e.g. --grid 8193 --out out/big).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
[ -f build/release/build.ninja ] || cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)" 2>&1 | tail -n 1
exec ./build/release/planetsculpt demo --out out/demo "$@"
