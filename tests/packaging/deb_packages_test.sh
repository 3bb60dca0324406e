#!/usr/bin/env bash
# deb_packages_test.sh CPACK BUILD_DIR SCRATCH VERSION CMAKE LIBDIR CONSUMER_SOURCE
# Builds the Debian packages of BUILD_DIR into SCRATCH, unpacks them with dpkg -x
# into one root and checks the installed tree: the programs run from it (version,
# rig check, a small demo), the man pages render, the unit points at the installed
# daemon, bash completion works, no two packages ship the same file, the host
# package depends on the libraries its program links, and a program of someone
# else's (CONSUMER_SOURCE) builds against liblightstage-dev with CMake's
# find_package and with pkg-config, and runs.
set -euo pipefail
cpack=$1 build=$2 scratch=$3 version=$4 cmake=$5 libdir=$6 consumer=$7

fail() { echo "FAIL: $*" >&2; exit 1; }
# grep that reads all its input: `grep -q` stops at the first match, and with
# pipefail the writer's SIGPIPE would then fail the check.
contains() { grep "$@" >/dev/null; }
rm -rf "$scratch"
mkdir -p "$scratch/debs" "$scratch/root"
root=$scratch/root

"$cpack" -G DEB -B "$scratch/debs" --config "$build/CPackConfig.cmake" >"$scratch/cpack.log" 2>&1 ||
  { cat "$scratch/cpack.log" >&2; fail "cpack -G DEB failed"; }

declare -A deb
for package in lightstage lightstage-domed lightstage-sim lightstage-rigs liblightstage-dev; do
  files=("$scratch/debs/${package}_${version}-"*.deb)
  [ -f "${files[0]}" ] || fail "no package file for $package in $scratch/debs: $(ls "$scratch/debs")"
  deb[$package]=${files[0]}
  dpkg-deb --field "${files[0]}" Package | contains -x "$package" || fail "${files[0]}: Package is not $package"
  dpkg -x "${files[0]}" "$root"
done

# Each file in exactly one package, or dpkg refuses to install them side by side.
for package in "${!deb[@]}"; do
  dpkg-deb --contents "${deb[$package]}" | awk '$1 !~ /^d/ { print $NF }'
done | sort | uniq -d >"$scratch/shared-files"
[ ! -s "$scratch/shared-files" ] || fail "files in more than one package: $(cat "$scratch/shared-files")"

# Where each package puts its files.
expect_in() {
  local package=$1 path=$2
  dpkg-deb --contents "${deb[$package]}" | awk '{ print $NF }' | contains -x "\./${path#/}" ||
    fail "$package does not contain /${path#/}"
}
expect_in lightstage usr/bin/lightstage
expect_in lightstage usr/share/man/man1/lightstage.1.gz
expect_in lightstage usr/share/bash-completion/completions/lightstage
expect_in lightstage usr/lib/udev/rules.d/70-lightstage.rules
expect_in lightstage usr/share/doc/lightstage/firmware.md
expect_in lightstage usr/share/doc/lightstage/rig-format.md
expect_in lightstage-domed usr/bin/lightstage-domed
expect_in lightstage-domed usr/share/man/man1/lightstage-domed.1.gz
expect_in lightstage-domed usr/lib/systemd/system/lightstage-domed.service
expect_in lightstage-domed usr/lib/sysusers.d/lightstage.conf
expect_in lightstage-domed usr/lib/udev/rules.d/60-lightstage-gpio.rules
expect_in lightstage-domed usr/libexec/lightstage/lightstage-gadget.sh
expect_in lightstage-sim usr/bin/lightstage-sim
expect_in lightstage-sim usr/share/man/man1/lightstage-sim.1.gz
expect_in lightstage-rigs usr/share/lightstage/rigs/sim-dome.yaml
expect_in liblightstage-dev usr/include/lightstage/pipeline/solve_methods.hpp
expect_in liblightstage-dev usr/include/lightstage/common/version.hpp
expect_in liblightstage-dev usr/include/lightstage/proto/controller.pb.h
expect_in liblightstage-dev "usr/$libdir/liblightstage_host.a"
expect_in liblightstage-dev "usr/$libdir/cmake/Lightstage/LightstageConfig.cmake"
expect_in liblightstage-dev "usr/$libdir/pkgconfig/lightstage.pc"
[ -x "$root/usr/libexec/lightstage/lightstage-gadget.sh" ] || fail "the gadget script is not executable"

# Control fields: library dependencies from dpkg-shlibdeps, the rigs package, maintainer scripts.
depends=$(dpkg-deb --field "${deb[lightstage]}" Depends)
for library in libopencv libprotobuf lightstage-rigs; do
  grep -q "$library" <<<"$depends" || fail "lightstage's Depends has no $library: $depends"
done
description=$(dpkg-deb --field "${deb[lightstage]}" Description)
[ "${description%%$'\n'*}" = "photometric stereo on a light stage: the host program" ] ||
  fail "lightstage's Description does not start with its synopsis: $description"
dpkg-deb --field "${deb[lightstage-domed]}" Depends | contains lightstage-rigs || fail "lightstage-domed does not depend on lightstage-rigs"
dpkg-deb --field "${deb[lightstage-rigs]}" Architecture | contains -x all || fail "lightstage-rigs is not Architecture: all"
dpkg-deb --info "${deb[lightstage-domed]}" postinst | contains "systemd-sysusers /usr/lib/sysusers.d/lightstage.conf" ||
  fail "lightstage-domed's postinst does not create the unit's user"

# The programs, from the unpacked tree.
rig=$root/usr/share/lightstage/rigs/sim-dome.yaml
"$root/usr/bin/lightstage" --version | contains "lightstage $version" || fail "lightstage --version"
"$root/usr/bin/lightstage-sim" --version | contains "$version" || fail "lightstage-sim --version"
"$root/usr/bin/lightstage-domed" --check --rig "$rig" || fail "lightstage-domed --check --rig $rig"
# 128 px: the smallest images whose chrome-sphere highlights calibrate every LED.
# One retry: on a machine loaded by parallel builds the simulated strobe can miss
# its deadline (STROBE_TIMEOUT), which says nothing about the packages.
run_demo() {
  "$root/usr/bin/lightstage" demo --scene sphere --width 128 --height 128 --programs "$root/usr/bin" --rig "$rig" \
    --out "$scratch/demo" --quiet 2>"$scratch/demo.err"
}
if ! run_demo; then
  if grep -q STROBE_TIMEOUT "$scratch/demo.err"; then
    echo "demo: strobe timeout, retrying once: $(cat "$scratch/demo.err")" >&2
    run_demo || fail "lightstage demo from the unpacked packages: $(cat "$scratch/demo.err")"
  else
    fail "lightstage demo from the unpacked packages: $(cat "$scratch/demo.err")"
  fi
fi
[ -f "$scratch/demo/demo.json" ] || fail "the demo wrote no demo.json"

# Man pages render, with the installed rig folder in the defaults (under the
# configured prefix, which the programs were built with), not the source tree's.
for program in lightstage lightstage-domed lightstage-sim; do
  page=$root/usr/share/man/man1/$program.1.gz
  MANWIDTH=80 man -l "$page" >"$scratch/$program.txt" 2>"$scratch/$program.man-errors" || fail "man -l $page"
  grep -q SYNOPSIS "$scratch/$program.txt" || fail "$program.1 has no SYNOPSIS"
  grep -q "$program \[OPTIONS\]" "$scratch/$program.txt" || fail "$program.1's synopsis does not name $program"
done
grep -q "share/lightstage/rigs/sim-dome.yaml" "$scratch/lightstage-domed.txt" ||
  fail "lightstage-domed.1 does not show the installed rig folder"

# The unit starts the daemon where the package put it.
unit=$root/usr/lib/systemd/system/lightstage-domed.service
! grep -q "@" "$unit" || fail "$unit has unsubstituted @VARIABLES@"
grep -q "^ExecStart=/usr/bin/lightstage-domed " "$unit" || fail "$unit: ExecStart is not /usr/bin/lightstage-domed"
grep -q "^User=lightstage" "$unit" || fail "$unit: no User=lightstage"
grep -q "^u lightstage " "$root/usr/lib/sysusers.d/lightstage.conf" || fail "sysusers.d entry has no user lightstage"

# Bash completion: subcommands and flags, read from the unpacked program's --help.
complete_words() {
  bash -c 'source "$1"; shift
           COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); COMPREPLY=()
           _lightstage; printf "%s\n" "${COMPREPLY[@]}"' _ \
    "$root/usr/share/bash-completion/completions/lightstage" "$@"
}
complete_words "$root/usr/bin/lightstage" de | contains -x demo || fail "completion: 'lightstage de' offers no demo"
complete_words "$root/usr/bin/lightstage" demo --wi | contains -x -- --width || fail "completion: 'lightstage demo --wi' offers no --width"
complete_words "$root/usr/bin/lightstage" demo --method ro | contains -x robust || fail "completion: 'lightstage demo --method ro' offers no robust"
# The library, from a program of someone else's: CMake's find_package (the
# package is found under the unpacked root, the dependencies on this machine)...
dev_depends=$(dpkg-deb --field "${deb[liblightstage-dev]}" Depends)
for package in libeigen3-dev libopencv-core-dev libprotobuf-dev; do
  grep -q "$package" <<<"$dev_depends" || fail "liblightstage-dev's Depends has no $package: $dev_depends"
done
readelf -S "$root/usr/$libdir/liblightstage_host.a" | contains debug_info && fail "liblightstage_host.a keeps its debug information"
"$cmake" -S "$consumer" -B "$scratch/consumer-cmake" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=$root/usr" \
  >"$scratch/consumer-cmake.log" 2>&1 || fail "find_package(Lightstage) from the unpacked packages: $(tail -20 "$scratch/consumer-cmake.log")"
"$cmake" --build "$scratch/consumer-cmake" >>"$scratch/consumer-cmake.log" 2>&1 ||
  fail "building against Lightstage::pipeline: $(tail -20 "$scratch/consumer-cmake.log")"
"$scratch/consumer-cmake/consumer" >"$scratch/consumer.out" || fail "the CMake consumer: $(cat "$scratch/consumer.out")"
contains "lightstage $version" "$scratch/consumer.out" || fail "the CMake consumer: $(cat "$scratch/consumer.out")"
# ... and pkg-config.
pc_dir=$root/usr/$libdir/pkgconfig
PKG_CONFIG_PATH=$pc_dir pkg-config --modversion lightstage | contains -x "$version" || fail "pkg-config --modversion lightstage"
read -r -a flags <<<"$(PKG_CONFIG_PATH=$pc_dir pkg-config --cflags --libs lightstage)"
c++ -std=c++20 -O1 -o "$scratch/consumer-pc" "$consumer/consumer.cpp" "${flags[@]}" 2>"$scratch/consumer-pc.log" ||
  fail "c++ \$(pkg-config --cflags --libs lightstage): $(tail -20 "$scratch/consumer-pc.log")"
"$scratch/consumer-pc" >"$scratch/consumer-pc.out" || fail "the pkg-config consumer: $(cat "$scratch/consumer-pc.out")"
cat "$scratch/consumer.out"
echo "packages: ${deb[*]}"
