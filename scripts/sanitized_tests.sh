#!/usr/bin/env bash
# `./irdist test --sanitize [ctest args]`: the whole suite built with ASan+UBSan (clang) in
# build-asan, then CTest on it (timeouts scaled; a sanitizer report from any process fails the
# run). The missing Debian packages (scripts/debian_packages.sh --clang) are installed before
# build-asan is configured.
set -euo pipefail

root="$(dirname "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")")"
asan="$root/build-asan"
jobs="$(nproc 2>/dev/null || echo 2)"
# As ./irdist sets them (ccache reuses one cache across checkouts of the tree).
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"

# clang (half gcc's compile time for this tree under ASan); a tree configured with another
# compiler is configured again from scratch.
if [ -f "$asan/CMakeCache.txt" ] && ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++' "$asan/CMakeCache.txt"; then
  rm -rf "$asan/CMakeCache.txt" "$asan/CMakeFiles" "$asan/build.ninja"
fi
if [ ! -f "$asan/build.ninja" ]; then
  "$root/scripts/debian_packages.sh" --clang
  launcher=()
  command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # No Python module: python3 does not load the sanitizers' runtime an instrumented module needs.
  cmake -S "$root" --preset asan -B "$asan" "${launcher[@]}" >&2  # CMakePresets.json
fi
# Also for a build-asan configured before these options. Line tables only (-g1): a report's
# stack still names file and line. -O2: with clang it compiles as fast as -O1, and the suite's
# fits run twice as fast.
cmake "$asan" -DIRDIST_TEST_TIMEOUT_SCALE=10 -DIRDIST_BUILD_PYTHON=OFF \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" >&2
cmake --build "$asan" --parallel "$jobs" >&2
cd "$asan"
# Every process of the run (tests, the irdist binaries and virtual rigs they start) writes any
# sanitizer report to sanitizer-reports/; one report fails the run, even from a process whose
# exit status nobody checks. GLib and Aravis keep allocations for the process's life: leaks are
# not reported.
reports="$asan/sanitizer-reports"
rm -rf "$reports"
mkdir -p "$reports"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}:log_path=$reports/asan"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}:log_path=$reports/ubsan"
status=0
ctest --output-on-failure --parallel "$jobs" "$@" || status=$?
if [ -n "$(ls -A "$reports")" ]; then
  echo "irdist test --sanitize: sanitizer reports (this fails the run):" >&2
  for report in "$reports"/*; do echo "--- $report" >&2; head -n 40 "$report" >&2; done
  status=1
fi
exit "$status"
