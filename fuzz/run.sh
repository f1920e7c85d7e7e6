#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each for a bounded time on a
# copy of its seed corpus (fuzz/corpus/<target>/; the repository's copy is never modified).
#   fuzz/run.sh [SECONDS_PER_TARGET=60] [TARGET...]
# Exits non-zero when a target finds a crash; the reproducer is left in build/fuzz/artifacts/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(planet_file heightmap_image sidecar_json stroke_journal session_sidecar stroke_script synth_script
                                 marker_layout calibration obj_triangles)
if ! command -v clang++ >/dev/null; then
  echo "fuzz: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2
  exit 2
fi
if [ ! -f build/fuzz/build.ninja ]; then
  # -O1 with line tables: libFuzzer's recommended level, a third of -O3's compile time under the
  # sanitizers (docs/CI.md).
  cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
        -DPS_FUZZ=ON -DPS_WERROR=OFF -DPS_BUILD_TESTS=OFF >/dev/null
fi
cmake --build build/fuzz -j"$(nproc)" --target $(printf 'fuzz_%s ' "${targets[@]}")
mkdir -p build/fuzz/artifacts
# One fuzzer per core at a time (each is single-threaded); each one's log is printed when it ends.
fuzz_one() {
  local t="$1" work log
  work="$(mktemp -d)"
  log="$(mktemp)"
  cp -r "fuzz/corpus/$t/." "$work/"
  local rc=0
  # Heightmap decoders print libpng/libtiff complaints on stderr: keep only libFuzzer's lines.
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "build/fuzz/fuzz/fuzz_$t" -max_total_time="$seconds" -max_len=16384 -rss_limit_mb=2048 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="build/fuzz/artifacts/$t-" "$work" 2>"$log" || rc=1
  { echo "== fuzz_$t: ${seconds}s$([ $rc = 0 ] || echo ': FOUND A CRASH')"
    grep -E '^(==|SUMMARY|stat::|Done|artifact|Test unit|#[0-9]+[[:space:]]+DONE)|ERROR' "$log" || true; } >&2
  rm -rf "$work" "$log"
  return $rc
}
status=0
pids=()
for t in "${targets[@]}"; do
  fuzz_one "$t" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$(nproc)" ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
