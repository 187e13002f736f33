#!/usr/bin/env bash
# Install the Debian packages occgt needs (only the missing ones), then configure and
# build a Release tree in build/. Idempotent: when everything is present it only runs
# the (incremental) build. Works as root or through sudo.
#
#   scripts/setup.sh            runtime + build dependencies, then build
#   scripts/setup.sh --test     also the test dependencies (python3-numpy, jsonschema, ...)
#   scripts/setup.sh --no-build only install packages
#   scripts/setup.sh --target T build only target T (scripts/occgt: --target occgt)
#   scripts/setup.sh --install  then `cmake --install` into $OCCGT_PREFIX (default ~/.local),
#                               which puts bin/occgt on PATH when PREFIX/bin is on it
set -euo pipefail
here="$(cd "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")/.." && pwd)"  # through a symlink too
# ccache keyed on paths relative to the checkout (and not on the build folder), so a
# second clone of the same sources (CI's fresh clone, a worktree) reuses the cache.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"

want_tests=0
do_build=1
do_install=0
targets=()
while (($#)); do
  case "$1" in
    --test) want_tests=1 ;;
    --no-build) do_build=0 ;;
    --install) do_install=1 ;;
    --target)
      [[ $# -ge 2 ]] || { echo "setup.sh: --target needs a target name (e.g. occgt)" >&2; exit 2; }
      targets+=(--target "$2"); shift ;;
    *) echo "setup.sh: unknown argument '$1' (expected --test, --no-build, --target T or --install)" >&2; exit 2 ;;
  esac
  shift
done

packages=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev libopencv-dev libopenexr-dev libpcl-dev liboctomap-dev libpng-dev libjpeg-dev zlib1g-dev libdeflate-dev liblz4-dev libssl-dev
  nlohmann-json3-dev libcli11-dev libyaml-cpp-dev libarchive-dev libzip-dev libtbb-dev libhdf5-dev libembree-dev
  libgtest-dev libbenchmark-dev libvalijson-dev gnuplot-nox
  pybind11-dev python3-dev
)
if [[ $want_tests == 1 ]]; then
  packages+=(python3 python3-numpy python3-jsonschema python3-yaml python3-pil python3-opencv mypy chromium python3-torch
    python3-venv python3-pip python3-setuptools python3-wheel)
fi
if [[ -n "${OCCGT_EXTRA_PACKAGES:-}" ]]; then
  read -r -a extra <<<"$OCCGT_EXTRA_PACKAGES"
  packages+=("${extra[@]}")
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "setup.sh: installing ${missing[*]}" >&2
  sudo_cmd=()
  if [[ $(id -u) != 0 ]]; then
    command -v sudo >/dev/null || { echo "setup.sh: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo_cmd=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [[ $do_build == 1 ]]; then
  build_dir="${OCCGT_BUILD_DIR:-$here/build}"
  if [[ ! -f "$build_dir/CMakeCache.txt" ]]; then
    cmake -S "$here" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >&2
  fi
  cmake --build "$build_dir" -j "$(nproc)" ${targets[@]+"${targets[@]}"} >&2
  if [[ $do_install == 1 ]]; then
    prefix="${OCCGT_PREFIX:-$HOME/.local}"
    cmake --install "$build_dir" --prefix "$prefix" >&2
    case ":$PATH:" in
      *":$prefix/bin:"*) echo "setup.sh: installed $prefix/bin/occgt" >&2 ;;
      *) echo "setup.sh: installed $prefix/bin/occgt; add $prefix/bin to PATH to run occgt" >&2 ;;
    esac
  fi
fi
