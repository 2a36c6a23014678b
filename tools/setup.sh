#!/usr/bin/env bash
# Installs what nonbloppy needs from Debian (only what is missing), then configures and
# builds it in Release. Safe to run again: with everything present it only rebuilds.
#   usage: bash tools/setup.sh [BUILD_DIR]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir="${1:-build}"

packages=(cmake g++ make pkg-config libopenvdb-dev libopenvdb-tools libtbb-dev libblosc-dev
          zlib1g-dev libexpat1-dev nlohmann-json3-dev clang libclang-rt-14-dev
          libboost-iostreams-dev googletest libgtest-dev libcli11-dev libbenchmark-dev doxygen locales
          pybind11-dev python3-dev python3-numpy)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DNONBLOPPY_BUILD_PYTHON=ON >/dev/null
cmake --build "$build_dir" -j"$(nproc)" -- --no-print-directory
