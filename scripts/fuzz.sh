#!/usr/bin/env bash
# `./irdist fuzz TARGET [SECONDS | --runs N [-max_len=B] [-max_total_time=S]]`,
# `./irdist fuzz --build`: the libFuzzer targets of fuzz/, built with clang, ASan and UBSan in
# build-fuzz/ (./irdist fuzz --help). The missing Debian packages (scripts/debian_packages.sh
# --clang) are installed before build-fuzz is configured.
set -euo pipefail

root="$(dirname "$(dirname "$(readlink -f "${BASH_SOURCE[0]}")")")"
fuzz="$root/build-fuzz"
# As ./irdist sets them (ccache reuses one cache across checkouts of the tree).
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"

fuzz_targets() { ls "$root/fuzz/corpus" | tr '\n' ' '; }

fuzz_usage() {
  cat <<USAGE
usage: ./irdist fuzz TARGET [SECONDS]    fuzz TARGET for SECONDS (default 60)
       ./irdist fuzz TARGET --runs N [-max_len=B] [-max_total_time=S]   fuzz TARGET for N
                                         executions, seed 1 (what CI runs), inputs at most B bytes
                                         (libFuzzer's default without it), at most S seconds
       ./irdist fuzz --build             build every target (before running several at once)
       ./irdist fuzz --help              this text
targets: $(fuzz_targets)
The corpus grows in build-fuzz/corpus/TARGET, seeded from fuzz/corpus/TARGET. A finding (crash, leak,
timeout, sanitizer report) is saved in build-fuzz/findings/TARGET/ and printed with the command that
reproduces it; the exit status is then 1. A --runs run records no allocation stacks (ASan's
malloc_context_size=0, the fuzzing 10% faster): the reproducing command prints them.
USAGE
}

# Prints each new finding of TARGET with the command that reproduces it.
fuzz_findings() {
  local target="$1" since="$2" finding
  while IFS= read -r finding; do
    echo "fuzz target $target: FINDING $finding" >&2
    echo "  reproduce: $fuzz/fuzz_$target $finding" >&2
  done < <(find "$fuzz/findings/$target" -type f -newer "$since" 2>/dev/null)
}

# Configures build-fuzz (once) and builds the given targets of it (all without one).
fuzz_build() {
  if [ ! -f "$fuzz/build.ninja" ]; then
    "$root/scripts/debian_packages.sh" --clang
    local launcher=()
    command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    cmake -S "$root/fuzz" -B "$fuzz" -G Ninja -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" >&2
  fi
  cmake --build "$fuzz" --parallel "$(nproc 2>/dev/null || echo 2)" "$@" >&2
}

target="${1:-}" limit=()
case "$target" in
  -h|--help|help) fuzz_usage; exit 0 ;;
  --build) fuzz_build; exit 0 ;;
  "") fuzz_usage >&2; exit 2 ;;
esac
if [ ! -d "$root/fuzz/corpus/$target" ]; then
  echo "irdist fuzz: unknown target '$target'" >&2; fuzz_usage >&2; exit 2
fi
case "${2:-60}" in
  --runs) [[ "${3:-}" =~ ^[0-9]+$ ]] || { fuzz_usage >&2; exit 2; }
          limit=(-runs="$3" -seed=1)
          for extra in "${@:4}"; do
            case "$extra" in
              -max_len=*|-max_total_time=*)
                [[ "${extra#*=}" =~ ^[0-9]+$ ]] || { fuzz_usage >&2; exit 2; }
                limit+=("$extra") ;;
              *) fuzz_usage >&2; exit 2 ;;
            esac
          done
          export ASAN_OPTIONS="${ASAN_OPTIONS:-malloc_context_size=0}" ;;
  *) [[ "${2:-60}" =~ ^[0-9]+$ ]] || { fuzz_usage >&2; exit 2; }
     limit=(-max_total_time="${2:-60}") ;;
esac
fuzz_build --target "fuzz_$target"
mkdir -p "$fuzz/corpus/$target" "$fuzz/findings/$target"
since="$fuzz/findings/.start-$target"
touch "$since"
if "$fuzz/fuzz_$target" "${limit[@]}" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$fuzz/findings/$target/" \
    "$fuzz/corpus/$target" "$root/fuzz/corpus/$target"; then
  exit 0
fi
fuzz_findings "$target" "$since"
exit 1
