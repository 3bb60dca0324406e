#!/usr/bin/env bash
# controller_package_test.sh CPACK BUILD_DIR SCRATCH VERSION ARCHITECTURE [EMULATOR]
# The controller board's packages from a controller-only build (the arm64 cross
# build): builds lightstage-domed and lightstage-rigs into SCRATCH, checks their
# architecture, dependencies and files, unpacks them with dpkg -x and runs the
# unpacked daemon (under EMULATOR when it is another architecture's): version,
# rig checks, the real GPIO backend's error for a missing chip, its man page.
set -euo pipefail
cpack=$1 build=$2 scratch=$3 version=$4 architecture=$5
emulator=("${@:6}")

fail() { echo "FAIL: $*" >&2; exit 1; }
contains() { grep "$@" >/dev/null; }  # reads all its input (see deb_packages_test.sh)
rm -rf "$scratch"
mkdir -p "$scratch/debs" "$scratch/root"
root=$scratch/root

"$cpack" -G DEB -B "$scratch/debs" --config "$build/CPackConfig.cmake" >"$scratch/cpack.log" 2>&1 ||
  { cat "$scratch/cpack.log" >&2; fail "cpack -G DEB failed"; }
ls "$scratch/debs"/*.deb >"$scratch/debs.txt"
[ "$(wc -l <"$scratch/debs.txt")" -eq 2 ] || fail "expected two packages, got: $(cat "$scratch/debs.txt")"

domed=$scratch/debs/lightstage-domed_${version}-1_${architecture}.deb
rigs=$scratch/debs/lightstage-rigs_${version}-1_all.deb
[ -f "$domed" ] || fail "no $domed: $(cat "$scratch/debs.txt")"
[ -f "$rigs" ] || fail "no $rigs: $(cat "$scratch/debs.txt")"
dpkg-deb --field "$domed" Architecture | contains -x "$architecture" || fail "$domed is not Architecture: $architecture"
depends=$(dpkg-deb --field "$domed" Depends)
for library in libgpiod2 libprotobuf libyaml-cpp libstdc++6 "lightstage-rigs (= $version-1)"; do
  grep -qF "$library" <<<"$depends" || fail "lightstage-domed's Depends has no $library: $depends"
done
dpkg-deb --info "$domed" postinst | contains "systemd-sysusers /usr/lib/sysusers.d/lightstage.conf" ||
  fail "lightstage-domed's postinst does not create the unit's user"

for path in usr/bin/lightstage-domed usr/share/man/man1/lightstage-domed.1.gz \
  usr/lib/systemd/system/lightstage-domed.service usr/lib/sysusers.d/lightstage.conf \
  usr/lib/udev/rules.d/60-lightstage-gpio.rules usr/libexec/lightstage/lightstage-gadget.sh; do
  dpkg-deb --contents "$domed" | awk '{ print $NF }' | contains -x "\./$path" || fail "lightstage-domed does not contain /$path"
done
dpkg-deb --contents "$domed" | awk '{ print $NF }' | contains "usr/bin/lightstage$" && fail "lightstage-domed carries the host program"
dpkg -x "$domed" "$root"
dpkg -x "$rigs" "$root"

# The program is the target's (e.g. "AArch64"), stripped.
daemon=$root/usr/bin/lightstage-domed
machine=$(readelf -h "$daemon" | sed -n 's/^ *Machine: *//p')
echo "lightstage-domed: $machine"
case "$architecture" in
  arm64) [ "$machine" = AArch64 ] || fail "$daemon is for $machine, not AArch64" ;;
  amd64) [ "$machine" = "Advanced Micro Devices X86-64" ] || fail "$daemon is for $machine, not x86-64" ;;
esac
readelf -S "$daemon" | contains debug_info && fail "$daemon is not stripped"
grep -q "^g gpio " "$root/usr/lib/sysusers.d/lightstage.conf" || fail "sysusers.d entry has no gpio group"
grep -q 'GROUP="gpio"' "$root/usr/lib/udev/rules.d/60-lightstage-gpio.rules" || fail "the udev rule gives no gpio group"

run() { "${emulator[@]}" "$daemon" "$@"; }
run --version | contains "$version" || fail "lightstage-domed --version"
for rig in "$root"/usr/share/lightstage/rigs/*.yaml; do
  run --check --rig "$rig" >"$scratch/check.log" 2>&1 || fail "--check --rig $rig: $(cat "$scratch/check.log")"
done
# The real libgpiod backend, on a chip that is not there: an error naming it, not 0.
status=0
run --check --rig "$root/usr/share/lightstage/rigs/sim-dome.yaml" --gpio gpiod:/dev/gpiochip-lightstage-missing \
  >"$scratch/missing.log" 2>&1 || status=$?
[ "$status" -ne 0 ] || fail "--check on a missing chip exited 0"
contains gpiochip-lightstage-missing "$scratch/missing.log" || fail "--check on a missing chip: $(cat "$scratch/missing.log")"

page=$root/usr/share/man/man1/lightstage-domed.1.gz
MANWIDTH=80 man -l "$page" >"$scratch/man.txt" 2>"$scratch/man-errors.txt" || fail "man -l $page"
grep -q "lightstage-domed \[OPTIONS\]" "$scratch/man.txt" || fail "lightstage-domed.1's synopsis does not name lightstage-domed"
grep -q "share/lightstage/rigs/sim-dome.yaml" "$scratch/man.txt" || fail "lightstage-domed.1 does not show the installed rig folder"
! grep -q "qemu" "$scratch/man.txt" || fail "lightstage-domed.1 names the emulator"
grep -q "^ExecStart=/usr/bin/lightstage-domed " "$root/usr/lib/systemd/system/lightstage-domed.service" ||
  fail "the unit does not start /usr/bin/lightstage-domed"
echo "packages: $domed $rigs"
