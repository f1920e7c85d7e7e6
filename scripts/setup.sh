#!/usr/bin/env bash
# Installs the Debian packages PlanetSculpt builds against. Idempotent: when everything is
# present it only runs dpkg-query and exits quietly.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libgtest-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev
  libopencv-dev libopencv-contrib-dev libapriltag-dev libtiff-dev libgdal-dev gdal-bin libpng-dev zlib1g-dev libcairo2-dev libyaml-dev libxml2-dev
  libcgal-dev
  libegl-dev libopengl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  libglfw3-dev libimgui-dev libstb-dev xvfb xauth
  clang libclang-rt-14-dev ccache python3
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "setup: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
if ! $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}" >/tmp/planetsculpt-apt.log 2>&1; then
  $SUDO apt-get update -q >>/tmp/planetsculpt-apt.log 2>&1
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}" >>/tmp/planetsculpt-apt.log 2>&1 || {
    echo "setup: apt-get failed; see /tmp/planetsculpt-apt.log" >&2
    tail -20 /tmp/planetsculpt-apt.log >&2
    exit 1
  }
fi
echo "setup: done" >&2
