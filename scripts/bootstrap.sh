#!/usr/bin/env bash
# Installs the Debian packages frontdt's build, tests and benchmarks need
# (only the missing ones), then configures build/ in release mode and
# compiles. Idempotent: a second run installs nothing and rebuilds only
# what changed. Usage: scripts/bootstrap.sh [extra meson setup options]
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential meson ninja-build pkg-config cmake
  libhwloc-dev hwloc libgmp-dev libmpfr-dev
  libcgal-dev libtet1.5-dev tetgen libboost-dev voro++-dev voro++
  libtbb-dev libqhull-dev
  python3 python3-vtk9 python3-meshio gmsh openfoam
  gnuplot-nox valgrind clang libclang-rt-14-dev
  python3-dev python3-numpy python3-scipy python3-mesonpy python3-venv
  locales gcovr
  mpi-default-dev mpi-default-bin
  libmpich-dev mpich
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "bootstrap: installing ${missing[*]}"
  sudo=()
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "bootstrap: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# A locale with a decimal comma for tests/test_reader.c's locale test
# (which fails without one when CI=true): de_DE.UTF-8, generated once.
if ! locale -a 2>/dev/null | grep -qix 'de_DE.utf8'; then
    echo "bootstrap: generating the de_DE.UTF-8 locale"
    sudo=()
    [[ $(id -u) -ne 0 ]] && sudo=(sudo)
    if ! grep -qx 'de_DE.UTF-8 UTF-8' /etc/locale.gen 2>/dev/null; then
        echo 'de_DE.UTF-8 UTF-8' | "${sudo[@]}" tee -a /etc/locale.gen >/dev/null
    fi
    "${sudo[@]}" locale-gen >/dev/null
fi

if [[ ! -f build/build.ninja ]]; then
  meson setup build --buildtype=release "$@"
fi
ninja -C build
