#!/usr/bin/env bash
# Configures and builds one flavour of the tree.
#   scripts/build.sh [release|sanitize|fuzz|arm64]   (default: release)
# Build folders: build/ (release), build-sanitize/, build-fuzz/, build-arm64/
# (the controller board's part, cross-built; scripts/install-deps.sh arm64
# installs its toolchain).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flavour=${1:-release}
case "$flavour" in
  # -g1 (line tables and function names) is what backtraces and perf need; full
  # debug information costs a quarter of the build time, and 40 % under the sanitizers.
  release)  dir=$root/build;          args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG") ;;
  # -O1: sanitizers are meant to run optimised a little; Eigen at -O0 is too slow for the solver tests
  # (the tests' own code and the CLI's flag binding compile at -O0: tests/CMakeLists.txt).
  # Shared libraries: every test then also runs the LIGHTSTAGE_SHARED_LIBS build.
  sanitize) dir=$root/build-sanitize; args=(-DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g1" -DLIGHTSTAGE_SANITIZE=ON
                                          -DLIGHTSTAGE_BUILD_BENCHMARKS=OFF -DLIGHTSTAGE_SHARED_LIBS=ON) ;;
  # Line tables only: enough for the fuzzers' stack traces, and the build is CI's longest.
  fuzz)     dir=$root/build-fuzz;     args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG"
                                          -DLIGHTSTAGE_FUZZ=ON -DLIGHTSTAGE_BUILD_TESTS=OFF
                                          -DCMAKE_CXX_COMPILER=clang++ -DLIGHTSTAGE_BUILD_BENCHMARKS=OFF) ;;
  # Packages install to /usr: the daemon looks for its rigs under the prefix it was built for.
  arm64)    dir=$root/build-arm64;    args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DLIGHTSTAGE_CONTROLLER_ONLY=ON
                                          -DCMAKE_TOOLCHAIN_FILE=$root/cmake/toolchains/aarch64-linux-gnu.cmake
                                          "-DLIGHTSTAGE_CROSS_ROOT=${LIGHTSTAGE_CROSS_ROOT:-$root/build-arm64/cross-root}"
                                          -DCMAKE_INSTALL_PREFIX=/usr) ;;
  *) echo "usage: $0 [release|sanitize|fuzz|arm64]" >&2; exit 2 ;;
esac
# Unity units (LIGHTSTAGE_UNITY_BUILD) make a whole-tree build a third shorter;
# LIGHTSTAGE_UNITY_BUILD=OFF suits an edit-compile loop, which recompiles one file.
args+=("-DLIGHTSTAGE_UNITY_BUILD=${LIGHTSTAGE_UNITY_BUILD:-ON}")
# ccache (scripts/install-deps.sh installs it) reuses unchanged compiles between
# builds; paths are hashed relative to the checkout, so a second clone reuses the
# tests' compiles too (unity units name their sources by absolute path).
if command -v ccache >/dev/null 2>&1 && [ "${LIGHTSTAGE_CCACHE:-ON}" != OFF ]; then
  args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR=$root CCACHE_NOHASHDIR=true
fi
jobs=${LIGHTSTAGE_JOBS:-$(nproc)}
cmake -S "$root" -B "$dir" -G Ninja "${args[@]}" >/dev/null
target=()
[ "$flavour" = fuzz ] && target=(--target fuzz_targets)  # only the fuzzers need the fuzz flags
cmake --build "$dir" -j "$jobs" "${target[@]}"
