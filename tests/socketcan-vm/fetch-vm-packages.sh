#!/bin/sh
# Fetch (never install) the Debian packages the SocketCAN test VM needs and
# unpack them into a cache dir:
#   linux-image-6.1.0-N-amd64 (newest available), busybox-static, can-utils.
# Idempotent: a second run with a complete cache does nothing (a few ms).
# Usage: fetch-vm-packages.sh [CACHE_DIR]   (default: $MAGLEV_VM_CACHE or
#        ${XDG_CACHE_HOME:-$HOME/.cache}/maglev-vm). Prints the cache dir.
set -eu
CACHE="${1:-${MAGLEV_VM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/maglev-vm}}"
mkdir -p "$CACHE"
if [ -f "$CACHE/.complete" ] && [ -f "$CACHE/kernel-version" ] &&
   [ -d "$CACHE/root/lib/modules/$(cat "$CACHE/kernel-version")" ] &&
   [ -x "$CACHE/root/bin/busybox" ] && [ -x "$CACHE/root/usr/bin/candump" ]; then
  echo "$CACHE"
  exit 0
fi
if ! apt-cache show busybox-static >/dev/null 2>&1; then
  apt-get update >/dev/null 2>&1 || true
fi
# Newest 6.1 stock (not cloud/rt) kernel image the archive offers.
KPKG=$(apt-cache search --names-only '^linux-image-6\.1\.0-[0-9]+-amd64$' | awk '{print $1}' |
       sort -t- -k4,4n | tail -1)
if [ -z "$KPKG" ]; then
  echo "fetch-vm-packages: no linux-image-6.1.0-*-amd64 in apt's lists" >&2
  exit 1
fi
DEBS="$CACHE/debs"
mkdir -p "$DEBS"
# apt-get download writes to the current directory; it runs as root or as a
# user (the _apt sandbox warning is harmless).
(cd "$DEBS" && for p in "$KPKG" busybox-static can-utils; do
   ls ${p}_*.deb >/dev/null 2>&1 || apt-get download "$p" >/dev/null 2>&1 || apt-get download "$p"
 done)
rm -rf "$CACHE/root"
mkdir -p "$CACHE/root"
for d in "$DEBS"/*.deb; do dpkg -x "$d" "$CACHE/root"; done
KVER=$(ls "$CACHE/root/lib/modules" | head -1)
echo "$KVER" > "$CACHE/kernel-version"
touch "$CACHE/.complete"
echo "$CACHE"
