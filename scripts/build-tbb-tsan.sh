#!/usr/bin/env bash
# Build oneTBB with ThreadSanitizer instrumentation for `scripts/test-sanitize tsan`
# (docs/RELIABILITY.md "Sanitizer builds"). Debian's libtbb is not instrumented, so TSan
# cannot see the synchronisation inside TBB's scheduler (google/sanitizers#1004).
#
#   scripts/build-tbb-tsan.sh [DEST]     DEST defaults to build-tsan/tbb-tsan
#
# Takes the source of exactly the version of the installed libtbb-dev (same headers, same
# ABI) from Debian's source archive through a private apt sources list (the system's
# sources are not touched), with Debian's patches applied, and builds only the tbb
# library (no tests, examples, tbbmalloc or tbbbind) with g++, RelWithDebInfo and
# -DTBB_SANITIZE=thread into DEST/install. Prints the CMake package folder (for
# -DTBB_DIR) on stdout; everything else goes to stderr. Idempotent: when DEST/install
# already holds a build of that version it only prints the folder.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ccache paths relative to the checkout, as in setup.sh (the source tree is under DEST).
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
dest="${1:-$here/build-tsan/tbb-tsan}"
mkdir -p "$dest"
dest="$(cd "$dest" && pwd)"
prefix="$dest/install"
pkgdir="$prefix/lib/cmake/TBB"

src_pkg="$(dpkg-query -W -f='${source:Package}' libtbb-dev 2>/dev/null || true)"
version="$(dpkg-query -W -f='${source:Version}' libtbb-dev 2>/dev/null || true)"
[[ -n $src_pkg && -n $version ]] || {
  echo "build-tbb-tsan.sh: libtbb-dev is not installed (run scripts/setup.sh)" >&2
  exit 1
}
stamp="$src_pkg $version g++ RelWithDebInfo TBB_SANITIZE=thread"
if [[ -f $prefix/occgt-tbb-tsan.stamp && $(cat "$prefix/occgt-tbb-tsan.stamp") == "$stamp" &&
  -f $pkgdir/TBBConfig.cmake ]]; then
  echo "$pkgdir"
  exit 0
fi

sudo_cmd=()
[[ $(id -u) != 0 ]] && sudo_cmd=(sudo)
if ! dpkg-query -W -f='${Status}' dpkg-dev 2>/dev/null | grep -q "install ok installed"; then
  # apt-get source unpacks with dpkg-source (dpkg-dev); installed the way setup.sh does.
  echo "build-tbb-tsan.sh: installing dpkg-dev" >&2
  [[ ${#sudo_cmd[@]} == 0 ]] || command -v sudo >/dev/null || {
    echo "build-tbb-tsan.sh: need root or sudo to install dpkg-dev" >&2
    exit 1
  }
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends dpkg-dev >/dev/null
fi

# A private apt configuration with deb-src lines only: its own sources list, package
# lists and cache under DEST/apt, so the system's apt state is left as it is.
codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-bookworm}")"
apt_dir="$dest/apt"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/cache/archives/partial"
keyring=/usr/share/keyrings/debian-archive-keyring.gpg
cat >"$apt_dir/sources.list" <<EOF
deb-src [signed-by=$keyring] http://deb.debian.org/debian $codename main
deb-src [signed-by=$keyring] http://deb.debian.org/debian $codename-updates main
deb-src [signed-by=$keyring] http://deb.debian.org/debian-security $codename-security main
EOF
apt_opts=(-o "Dir::Etc::SourceList=$apt_dir/sources.list" -o Dir::Etc::SourceParts=/dev/null
  -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir/cache"
  -o APT::Sandbox::User=root)
echo "build-tbb-tsan.sh: fetching the source of $src_pkg $version" >&2
apt-get "${apt_opts[@]}" update -qq >&2
rm -rf "$dest/src"
mkdir -p "$dest/src"
(cd "$dest/src" && apt-get "${apt_opts[@]}" source -qq "$src_pkg=$version" >&2)
srcdir="$(find "$dest/src" -mindepth 1 -maxdepth 1 -type d -name "$src_pkg-*" | head -n1)"
[[ -n $srcdir && -f $srcdir/CMakeLists.txt ]] || {
  echo "build-tbb-tsan.sh: no unpacked source tree in $dest/src" >&2
  exit 1
}

echo "build-tbb-tsan.sh: building $srcdir with -DTBB_SANITIZE=thread" >&2
rm -rf "$dest/build" "$prefix"
cmake -S "$srcdir" -B "$dest/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=g++ -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_INSTALL_PREFIX="$prefix" \
  -DCMAKE_INSTALL_LIBDIR=lib -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF \
  -DTBB_STRICT=OFF -DTBBMALLOC_BUILD=OFF -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON \
  -DBUILD_SHARED_LIBS=ON >&2
cmake --build "$dest/build" --target tbb -j "${OCCGT_SANITIZE_JOBS:-$(nproc)}" >&2
cmake --install "$dest/build" >&2
[[ -f $pkgdir/TBBConfig.cmake ]] || {
  echo "build-tbb-tsan.sh: no TBBConfig.cmake in $pkgdir after the install" >&2
  exit 1
}
echo "$stamp" >"$prefix/occgt-tbb-tsan.stamp"
echo "$pkgdir"
