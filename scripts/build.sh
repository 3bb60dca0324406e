#!/usr/bin/env bash
# Configures and builds one flavour of the tree.
#   scripts/build.sh [release|sanitize|fuzz]   (default: release)
# Build folders: build/ (release), build-sanitize/, build-fuzz/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flavour=${1:-release}
case "$flavour" in
  release)  dir=$root/build;          args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo) ;;
  # -O1: sanitizers are meant to run optimised a little; Eigen at -O0 is too slow for the solver tests.
  sanitize) dir=$root/build-sanitize; args=(-DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g" -DLIGHTSTAGE_SANITIZE=ON
                                          -DLIGHTSTAGE_BUILD_BENCHMARKS=OFF) ;;
  fuzz)     dir=$root/build-fuzz;     args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DLIGHTSTAGE_FUZZ=ON -DLIGHTSTAGE_BUILD_TESTS=OFF
                                          -DCMAKE_CXX_COMPILER=clang++ -DLIGHTSTAGE_BUILD_BENCHMARKS=OFF) ;;
  *) echo "usage: $0 [release|sanitize|fuzz]" >&2; exit 2 ;;
esac
jobs=${LIGHTSTAGE_JOBS:-$(nproc)}
cmake -S "$root" -B "$dir" -G Ninja "${args[@]}" >/dev/null
target=()
[ "$flavour" = fuzz ] && target=(--target fuzz_targets)  # only the fuzzers need the fuzz flags
cmake --build "$dir" -j "$jobs" "${target[@]}"
