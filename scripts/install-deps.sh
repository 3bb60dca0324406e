#!/usr/bin/env bash
# Installs every Debian 12 package that building and testing Lightstage needs.
#   scripts/install-deps.sh [FLAVOUR...]   (the flavours of scripts/build.sh)
# With fuzz also clang and its libFuzzer runtime. With arm64 also the controller
# board's cross build: Debian's arm64 cross toolchain, the multiarch arm64 -dev
# packages and qemu's user-mode emulator (which runs the cross-built tests), and
# unpacks into build-arm64/cross-root (or $LIGHTSTAGE_CROSS_ROOT) the arm64 -dev
# packages that cannot be installed beside their amd64 twins.
# Idempotent: a no-op (no apt-get call at all) when everything is present.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
arm64=false
fuzz=false
for flavour in "$@"; do
  [ "$flavour" = arm64 ] && arm64=true
  [ "$flavour" = fuzz ] && fuzz=true
done

packages=(
  build-essential cmake ninja-build pkg-config git
  lld ccache  # faster links; compiles reused between builds and clones (scripts/build.sh)
  libeigen3-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-photo-dev
  libopenexr-dev libraw-dev libpng-dev libjpeg62-turbo-dev libtiff-dev libexiv2-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libcpp-httplib-dev  # the operator's station's HTTP server (lightstage serve)
  libgtest-dev libgmock-dev libbenchmark-dev
  libgpiod-dev libusb-1.0-0-dev libcamera-dev
  libgphoto2-dev libaravis-dev  # DSLRs over USB and GenICam cameras (host only: not in cross_packages)
  libprotobuf-dev protobuf-compiler zlib1g-dev
  pybind11-dev python3-dev python3-numpy  # the Python module (host/python) and its test
  chromium  # the report viewer's headless-browser test (tests/report)
  help2man man-db  # man pages from --help (packaging/) and the packaging test reading them
)
# That test drives Chromium from Node (npm ci at build time); Debian's own
# nodejs + npm only when the machine has no node of its own (e.g. NodeSource).
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

# The arm64 cross build of common/, hw/ and firmware/ (cmake/toolchains/aarch64-linux-gnu.cmake).
# yaml-cpp's -dev package is not multiarch: its arm64 one is unpacked, not installed.
cross_packages=(
  crossbuild-essential-arm64 qemu-user-static
  libopencv-core-dev:arm64 libfmt-dev:arm64 libspdlog-dev:arm64 libyaml-cpp0.7:arm64
  libprotobuf-dev:arm64 zlib1g-dev:arm64 libgpiod-dev:arm64 libusb-1.0-0-dev:arm64 libcamera-dev:arm64
  libgtest-dev:arm64 libgmock-dev:arm64
)
unpacked_cross_packages=(libyaml-cpp-dev:arm64 libyaml-cpp0.7:arm64)
cross_root=${LIGHTSTAGE_CROSS_ROOT:-$root/build-arm64/cross-root}
$arm64 && packages+=("${cross_packages[@]}")
$fuzz && packages+=(clang libclang-rt-14-dev)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
unpack=false
$arm64 && [ ! -f "$cross_root/usr/lib/aarch64-linux-gnu/cmake/yaml-cpp/yaml-cpp-config.cmake" ] && unpack=true
[ ${#missing[@]} -eq 0 ] && ! $unpack && exit 0

sudo=()
[ "$(id -u)" -ne 0 ] && sudo=(sudo)
export DEBIAN_FRONTEND=noninteractive
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  if $arm64 && ! dpkg --print-foreign-architectures | grep -qx arm64; then
    "${sudo[@]}" dpkg --add-architecture arm64
  fi
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if $unpack; then
  echo "install-deps: unpacking ${unpacked_cross_packages[*]} into $cross_root" >&2
  downloads=$(mktemp -d)
  trap 'rm -rf "$downloads"' EXIT
  chmod 0777 "$downloads"  # apt-get download runs as user _apt where it can
  (cd "$downloads" && apt-get download -qq "${unpacked_cross_packages[@]}")
  mkdir -p "$cross_root"
  for deb in "$downloads"/*.deb; do
    dpkg -x "$deb" "$cross_root"
  done
fi
