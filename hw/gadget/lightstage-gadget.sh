#!/bin/sh
# Makes the controller board a USB gadget through configfs (libcomposite), so
# the host reaches lightstage-domed over the USB cable. See hw/docs/links.md.
#
#   lightstage-gadget.sh up acm    CDC-ACM serial function: the board gets /dev/ttyGS0,
#                                  the host /dev/ttyACM* (serial: links). Binds at once.
#   lightstage-gadget.sh up ffs    FunctionFS function mounted at $LIGHTSTAGE_FFS_MOUNT
#                                  (ffs: on the board, usb:VID:PID on the host).
#                                  Start `lightstage-domed --listen ffs:MOUNT` next: it
#                                  writes the USB descriptors; then run `bind`.
#   lightstage-gadget.sh up both   both functions in one configuration
#   lightstage-gadget.sh bind      bind to the UDC (for ffs: waits until the daemon has
#                                  written its descriptors, i.e. MOUNT/ep1 exists)
#   lightstage-gadget.sh down      unbind and remove everything this script made
#
# Settings (environment): LIGHTSTAGE_USB_VID / _PID (default 0x1209 / 0x0001, the
# pid.codes test IDs: fine on a bench, a product needs its own), LIGHTSTAGE_USB_SERIAL
# (default: from /etc/machine-id), LIGHTSTAGE_FFS_MOUNT (default /dev/usb-ffs/lightstage),
# LIGHTSTAGE_FFS_USER (owner of the endpoint files, default root), LIGHTSTAGE_UDC
# (default: the first in /sys/class/udc), LIGHTSTAGE_BIND_TIMEOUT (seconds, default 30).
set -eu

VID=${LIGHTSTAGE_USB_VID:-0x1209}
PID=${LIGHTSTAGE_USB_PID:-0x0001}
SERIAL=${LIGHTSTAGE_USB_SERIAL:-$(cut -c1-16 /etc/machine-id 2>/dev/null || echo 0001)}
MOUNT=${LIGHTSTAGE_FFS_MOUNT:-/dev/usb-ffs/lightstage}
FFS_USER=${LIGHTSTAGE_FFS_USER:-root}
BIND_TIMEOUT=${LIGHTSTAGE_BIND_TIMEOUT:-30}
CONFIGFS=/sys/kernel/config
GADGET=$CONFIGFS/usb_gadget/lightstage
FFS_NAME=lightstage  # the function is ffs.$FFS_NAME; mount's "device" name must match

die() { echo "lightstage-gadget: $*" >&2; exit 1; }

find_udc() {
  if [ -n "${LIGHTSTAGE_UDC:-}" ]; then echo "$LIGHTSTAGE_UDC"; return; fi
  for udc in /sys/class/udc/*; do
    if [ -e "$udc" ]; then basename "$udc"; return; fi
  done
  die "no USB device controller in /sys/class/udc (is the port in peripheral/OTG mode? e.g. dtoverlay=dwc2 on a Raspberry Pi)"
}

up() {
  mode=$1
  case "$mode" in acm|ffs|both) ;; *) die "up: expected acm, ffs or both, got '$mode'" ;; esac
  modprobe libcomposite 2>/dev/null || true
  mountpoint -q "$CONFIGFS" || mount -t configfs none "$CONFIGFS"
  [ -d "$CONFIGFS/usb_gadget" ] || die "$CONFIGFS/usb_gadget missing: kernel without CONFIG_USB_CONFIGFS"
  [ ! -e "$GADGET" ] || die "$GADGET exists already (run '$0 down' first)"
  mkdir "$GADGET"
  cd "$GADGET"
  echo "$VID" > idVendor
  echo "$PID" > idProduct
  echo 0x0100 > bcdDevice
  echo 0x0200 > bcdUSB
  # Our FunctionFS descriptors cover full and high speed; keep a USB 3 UDC at high speed.
  [ ! -e max_speed ] || echo high-speed > max_speed
  mkdir -p strings/0x409
  echo "$SERIAL" > strings/0x409/serialnumber
  echo "Lightstage" > strings/0x409/manufacturer
  echo "Lightstage dome controller" > strings/0x409/product
  mkdir -p configs/c.1/strings/0x409
  echo "Lightstage controller" > configs/c.1/strings/0x409/configuration
  echo 100 > configs/c.1/MaxPower
  if [ "$mode" = acm ] || [ "$mode" = both ]; then
    mkdir -p functions/acm.usb0 || die "no CDC-ACM function: kernel without CONFIG_USB_CONFIGFS_ACM"
    ln -s functions/acm.usb0 configs/c.1/
  fi
  if [ "$mode" = ffs ] || [ "$mode" = both ]; then
    mkdir -p "functions/ffs.$FFS_NAME" || die "no FunctionFS: kernel without CONFIG_USB_CONFIGFS_F_FS"
    ln -s "functions/ffs.$FFS_NAME" configs/c.1/
    mkdir -p "$MOUNT"
    uid=$(id -u "$FFS_USER")
    gid=$(id -g "$FFS_USER")
    mount -t functionfs -o "uid=$uid,gid=$gid" "$FFS_NAME" "$MOUNT"
    echo "FunctionFS mounted at $MOUNT: start 'lightstage-domed --listen ffs:$MOUNT', then '$0 bind'"
  else
    bind
  fi
}

bind() {
  [ -d "$GADGET" ] || die "no gadget: run '$0 up ...' first"
  if [ -e "$GADGET/functions/ffs.$FFS_NAME" ]; then
    # The kernel refuses to bind a FunctionFS function before its descriptors are written.
    waited=0
    while [ ! -e "$MOUNT/ep1" ]; do
      [ "$waited" -lt "$BIND_TIMEOUT" ] || die "no $MOUNT/ep1 after ${BIND_TIMEOUT}s: is lightstage-domed listening on ffs:$MOUNT?"
      sleep 1
      waited=$((waited + 1))
    done
  fi
  udc=$(find_udc)
  echo "$udc" > "$GADGET/UDC"
  echo "gadget bound to $udc (VID:PID $VID:$PID, serial $SERIAL)"
}

down() {
  [ -d "$GADGET" ] || return 0
  cd "$GADGET"
  [ -z "$(cat UDC 2>/dev/null)" ] || echo "" > UDC
  for link in configs/c.1/acm.usb0 "configs/c.1/ffs.$FFS_NAME"; do
    [ ! -L "$link" ] || rm "$link"
  done
  ! mountpoint -q "$MOUNT" || umount "$MOUNT"
  for dir in configs/c.1/strings/0x409 configs/c.1 functions/acm.usb0 "functions/ffs.$FFS_NAME" strings/0x409; do
    [ ! -d "$dir" ] || rmdir "$dir"
  done
  cd /
  rmdir "$GADGET"
}

case "${1:-}" in
  up) up "${2:-}" ;;
  bind) bind ;;
  down) down ;;
  *) sed -n '2,22p' "$0" >&2; exit 2 ;;
esac
