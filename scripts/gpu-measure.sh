#!/usr/bin/env bash
# `bench render` and `bench frame` on a GPU machine that has no build of ours: a bare CUDA image
# with NVIDIA's driver but none of our libraries, reached with a copy of this tree. Run from the
# repository root: OUT=/some/dir bash scripts/gpu-measure.sh
#
# It needs, beside the tree (both ignored, made on the build machine):
#   .gpukit/kit.tar.xz  the stripped release binary and the shared libraries it loads, glibc's
#                       and OpenGL's left out (libraries these benches never call are stubs);
#                       made by scripts/gpu-kit.py
#   .gl/*.deb           glvnd's loaders (libEGL, libOpenGL, libGLX...), which dispatch to the
#                       NVIDIA driver; unpacked onto / (GPU_MEASURE_SKIP_GL=1 skips that, for a
#                       trial run on a machine that has its own)
# Writes $OUT/NAME.jsonl for each bench (the benches' JSON lines; render and frame unless
# GPU_MEASURE_BENCHES names others, see below) and $OUT/log.txt.
set -u
cd "$(dirname "$0")/.."
: "${OUT:?set OUT to the folder for the results}"
mkdir -p "$OUT"
export PATH=$PATH:/usr/sbin:/sbin  # ldconfig

measure() {
  echo "== gpu-measure $(date -u +%FT%TZ) in $PWD"
  if [ "${GPU_MEASURE_SKIP_GL:-0}" != 1 ]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
  fi
  # The driver's EGL vendor file: where the container runtime put it, else the driver's folder.
  if ! ls /usr/share/glvnd/egl_vendor.d/*nvidia* /etc/glvnd/egl_vendor.d/*nvidia* >/dev/null 2>&1 &&
    [ -e /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  fi
  echo "EGL vendors: ${__EGL_VENDOR_LIBRARY_FILENAMES:-$(ls /usr/share/glvnd/egl_vendor.d/ \
    /etc/glvnd/egl_vendor.d/ 2>/dev/null | tr '\n' ' ')}"

  # The kit, unpacked outside the tree (xz may be missing there; Python's tarfile reads it too).
  local kit=${GPU_MEASURE_KIT:-/tmp/gpukit/kit}
  if [ ! -x "$kit/planetsculpt" ]; then
    mkdir -p "$(dirname "$kit")"
    if command -v xz >/dev/null; then
      tar -C "$(dirname "$kit")" -xJf .gpukit/kit.tar.xz
    else
      python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' \
        .gpukit/kit.tar.xz "$(dirname "$kit")"
    fi
  fi
  cat "$kit/KIT-INFO"
  local bin=$kit/planetsculpt

  # The kit's libstdc++, libgcc_s and libdrm only where the machine has none (or too old a one):
  # a newer C++ runtime of the machine's serves our older libraries too.
  local fb=/tmp/gpukit/fallback-used
  mkdir -p "$fb"
  for f in "$kit"/fallback/*; do
    ldconfig -p | grep -q "^[[:space:]]*$(basename "$f") " || ln -sf "$f" "$fb/"
  done
  # NVIDIA's own libraries (libEGL_nvidia...) where the loader's cache does not list them.
  local nv=
  if ! ldconfig -p | grep -q libEGL_nvidia && [ -d /usr/local/nvidia/lib64 ]; then
    nv=:/usr/local/nvidia/lib64
  fi
  export LD_LIBRARY_PATH=$kit/lib:$fb$nv
  if ldd "$bin" 2>&1 | grep -q "not found"; then ln -sf "$kit"/fallback/* "$fb/"; fi
  echo "kit fallback libraries used: $(ls "$fb" | tr '\n' ' '); LD_LIBRARY_PATH=$LD_LIBRARY_PATH"

  echo "== machine"
  nvidia-smi -L || echo "no nvidia-smi"
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv,noheader
  ldconfig -p | grep -E "libEGL_nvidia|libnvidia-eglcore" || echo "no libEGL_nvidia in the loader's cache"
  ldd --version | head -1
  echo "nproc $(nproc)"
  echo "== libraries not found (none expected):"
  ldd "$bin" 2>&1 | grep "not found"
  echo "== libraries from outside the kit (glibc's and OpenGL's expected):"
  ldd "$bin" 2>&1 | grep "=>" | grep -v "$kit/lib\|$fb"

  # The tree's data (data/demo.mkv, calib/, markers/) from this copy, not the build's path.
  export PLANETSCULPT_SOURCE_DIR=$PWD
  # Each entry NAME:SECONDS[:VAR=VALUE,...]: `bench NAME` under that limit and those variables
  # (e.g. deform:300:OMP_NUM_THREADS=2 for a CPU bench on the machine's quiet cores).
  local b name limit vars
  for b in ${GPU_MEASURE_BENCHES:-render:90 frame:200}; do
    IFS=: read -r name limit vars <<<"$b"
    echo "== bench $name (limit ${limit}s${vars:+, $vars})"
    env ${vars//,/ } timeout "$limit" "$bin" bench "$name" >"$OUT/$name.jsonl"
    echo "rc $? ($(wc -l <"$OUT/$name.jsonl") lines)"
  done
  nvidia-smi --query-gpu=clocks.sm,clocks.mem --format=csv,noheader
  echo "== summary"
  python3 - "$OUT" <<'EOF'
import json, sys
import os
for name in ("render", "frame"):
    if not os.path.exists(f"{sys.argv[1]}/{name}.jsonl"):
        continue
    for line in open(f"{sys.argv[1]}/{name}.jsonl"):
        r = json.loads(line)
        keys = ("view", "case", "dist_max_px", "shading", "skipped", "reason", "ms", "ssim", "triangles",
                "fps", "frame_ms", "track_ms", "tessellate_ms", "render_ms", "overview_ms_when_drawn")
        gl = r.get("gl_renderer") or r.get("machine", {}).get("gl_renderer")
        print(name, {k: r[k] for k in keys if k in r}, gl or "")
EOF
  echo "== done $(date -u +%FT%TZ)"
}

measure 2>&1 | tee -a "$OUT/log.txt"
