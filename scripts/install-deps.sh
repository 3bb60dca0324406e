#!/usr/bin/env bash
# Installs every Debian 12 package that building and testing Lightstage needs.
# Idempotent: a no-op (no apt-get call at all) when everything is present.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  clang libclang-rt-14-dev
  libeigen3-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-photo-dev
  libopenexr-dev
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libgpiod-dev libusb-1.0-0-dev libcamera-dev
  libprotobuf-dev protobuf-compiler zlib1g-dev
  pybind11-dev python3-dev python3-numpy  # the Python module (host/python) and its test
  chromium  # the report viewer's headless-browser test (tests/report)
  help2man man-db  # man pages from --help (packaging/) and the packaging test reading them
)
# That test drives Chromium from Node (npm ci at build time); Debian's own
# nodejs + npm only when the machine has no node of its own (e.g. NodeSource).
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo=()
[ "$(id -u)" -ne 0 ] && sudo=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
