#!/usr/bin/env bash
# The Debian packages irdist's build, tests and tools need, and their install: only the missing
# ones (dpkg-query says which), with apt-get, through sudo when not root. Run by ./irdist before it
# configures a build tree and on every `./irdist build`; nothing is installed when nothing is
# missing.
#   scripts/debian_packages.sh                  the packages of the build (build/) and its tests
#   scripts/debian_packages.sh --clang          also clang and its runtime (./irdist fuzz,
#                                               ./irdist test --sanitize)
#   scripts/debian_packages.sh --list [--clang] print the names, one a line; install nothing
set -euo pipefail

packages=(
  g++ cmake ninja-build pkg-config
  lld  # links the executables several times faster than GNU ld (CMakeLists.txt)
  libaravis-dev aravis-tools aravis-tools-cli libusb-1.0-0-dev  # aravis-tools-cli: arv-tool-0.8 (docs/virtual-rig.md, discovery)
  libeigen3-dev libopencv-dev libceres-dev libboost-dev libyaml-cpp-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libssl-dev  # libcrypto: SHA-256 of recorded frames (acquisition/content_hash.h)
  gnuplot-nox
  xvfb  # tests/app/live/view_test.cc checks `irdist view` on a virtual X display (skips without it)
  python3-dev pybind11-dev python3-pybind11 python3-numpy  # the Python module (python/)
)
clang_packages=(clang libclang-rt-14-dev)  # libclang-rt: the sanitizers' and libFuzzer's runtime

list=0
for arg in "$@"; do
  case "$arg" in
    --clang) packages+=("${clang_packages[@]}") ;;
    --list) list=1 ;;
    *) echo "usage: scripts/debian_packages.sh [--clang] [--list]" >&2; exit 2 ;;
  esac
done
if ((list)); then
  printf '%s\n' "${packages[@]}"
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed$' || missing+=("$p")
done
((${#missing[@]})) || exit 0
echo "irdist: installing missing Debian packages: ${missing[*]}" >&2
sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "irdist: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
"${sudo[@]}" apt-get update -qq
# Through env: sudo would drop DEBIAN_FRONTEND from the environment (its env_reset).
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
  "${missing[@]}" >&2
