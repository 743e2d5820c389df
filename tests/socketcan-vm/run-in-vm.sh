#!/bin/bash
# Boot Debian's stock 6.1 kernel under QEMU (TCG) with a busybox initramfs,
# bring up vcan0 (CAN FD, MTU 72), run a command inside, return its exit code.
#
#   run-in-vm.sh [--share DIR]... [--out DIR] [--timeout SEC] [--] COMMAND [ARGS...]
#
# * Host /usr is shared read-only at /usr (so the host's dynamically linked
#   test programs run unchanged: /lib and /lib64 point into it), the
#   fetched Debian packages' root (can-utils: candump, cansend) at /opt/vmroot,
#   first on PATH.
# * Every --share DIR (default: the current directory) is mounted at the SAME
#   absolute path in the guest, read-write, so build-tree paths just work and
#   result files written there come back to the host.
# * COMMAND runs with /bin/sh in the current directory. To run several
#   processes (e.g. a plant and a controller over vcan0), pass a shell line:
#     run-in-vm.sh sh -c 'ctrl --can vcan0 & plant --can vcan0; rc=$?; wait $! && exit $rc'
#   The guest's console (stdout+stderr of COMMAND) is printed after the run;
#   --out DIR also keeps it as DIR/console.log.
# * Exit code: COMMAND's; 124 if the VM timed out; 125 if it could not boot.
# Environment: MAGLEV_VM_CACHE (cache dir, default ~/.cache/maglev-vm),
#   MAGLEV_VM_TIMEOUT (default 120 s), MAGLEV_VM_MEM (default 512M).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
SHARES=()
OUT=""
TIMEOUT="${MAGLEV_VM_TIMEOUT:-120}"
while [ $# -gt 0 ]; do
  case "$1" in
    --share) SHARES+=("$(cd "$2" && pwd)"); shift 2 ;;
    --out) mkdir -p "$2"; OUT="$(cd "$2" && pwd)"; shift 2 ;;
    --timeout) TIMEOUT="$2"; shift 2 ;;
    --) shift; break ;;
    *) break ;;
  esac
done
if [ $# -eq 0 ]; then
  echo "usage: run-in-vm.sh [--share DIR]... [--out DIR] [--timeout SEC] [--] COMMAND..." >&2
  exit 2
fi
[ ${#SHARES[@]} -eq 0 ] && SHARES=("$PWD")

CACHE="$("$HERE/fetch-vm-packages.sh" | tail -1)"
ROOT="$CACHE/root"
KVER="$(cat "$CACHE/kernel-version")"
MODDIR="$ROOT/lib/modules/$KVER"

# ---- kernel: uncompressed vmlinux (PVH entry, boots ~2x faster) or vmlinuz --
KERNEL="$CACHE/vmlinux-$KVER"
if [ ! -s "$KERNEL" ]; then
  VMLINUZ="$ROOT/boot/vmlinuz-$KVER"
  OFF=$(LC_ALL=C grep -aobUP '\xfd7zXZ\x00' "$VMLINUZ" | head -1 | cut -d: -f1 || true)
  if [ -n "$OFF" ]; then
    tail -c +$((OFF + 1)) "$VMLINUZ" | xz -dc > "$KERNEL.tmp" 2>/dev/null || true
  fi
  if [ -s "$KERNEL.tmp" ] && [ "$(head -c 4 "$KERNEL.tmp" | od -An -tx1 | tr -d ' ')" = "7f454c46" ]; then
    mv "$KERNEL.tmp" "$KERNEL"
  else
    rm -f "$KERNEL.tmp"
    KERNEL="$VMLINUZ"
  fi
fi

# ---- initramfs: busybox, the modules in dependency order, /init --------------
WANT_MODULES="can can-raw can-dev vcan virtio_pci 9pnet_virtio 9p"
INITRD="$CACHE/initramfs-$KVER-$(cat "$0" | md5sum | cut -c1-8).cpio"
if [ ! -s "$INITRD" ]; then
  STAGE="$(mktemp -d)"
  trap 'rm -rf "$STAGE"' EXIT
  mkdir -p "$STAGE"/{bin,sbin,proc,sys,dev,tmp,usr,opt/vmroot,modules,maglev-ctl,etc}
  cp "$ROOT/bin/busybox" "$STAGE/bin/busybox"
  ln -s usr/lib "$STAGE/lib"
  ln -s usr/lib64 "$STAGE/lib64"
  # Resolve dependencies from the .ko files (the package has no modules.dep).
  declare -A SEEN=()
  ORDER=()
  find_ko() { find "$MODDIR" -name "$1.ko" -o -name "$(echo "$1" | tr _ -).ko" -o -name "$(echo "$1" | tr - _).ko" | head -1; }
  visit() {
    local name="$1" ko dep
    [ -n "${SEEN[$name]:-}" ] && return 0
    SEEN[$name]=1
    ko="$(find_ko "$name")"
    if [ -z "$ko" ]; then
      # Built into the kernel?
      grep -q "/$(echo "$name" | tr - _).ko$\|/$(echo "$name" | tr _ -).ko$" "$MODDIR/modules.builtin" 2>/dev/null && return 0
      echo "run-in-vm: module $name not found" >&2
      return 1
    fi
    for dep in $(modinfo -F depends "$ko" | tr ',' ' '); do visit "$dep"; done
    ORDER+=("$ko")
  }
  for m in $WANT_MODULES; do visit "$m"; done
  : > "$STAGE/modules/order"
  for ko in "${ORDER[@]}"; do
    cp "$ko" "$STAGE/modules/"
    echo "$(basename "$ko")" >> "$STAGE/modules/order"
  done
  cat > "$STAGE/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/opt/vmroot/usr/bin:/opt/vmroot/bin:/bin:/sbin:/usr/bin:/usr/sbin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
for m in $(cat /modules/order); do insmod /modules/$m || echo "insmod $m failed"; done
O="trans=virtio,version=9p2000.L,msize=512000,cache=none"
mount -t 9p -o "$O" ctl /maglev-ctl || { echo "MAGLEV_VM_EXIT=125 (no 9p)"; poweroff -f; }
mount -t 9p -o "$O,ro" usr /usr
mount -t 9p -o "$O,ro" vmroot /opt/vmroot
. /maglev-ctl/mounts.sh
ip link set lo up
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set vcan0 up
cd "$(cat /maglev-ctl/cwd)"
/bin/sh /maglev-ctl/cmd.sh
rc=$?
echo $rc > /maglev-ctl/rc
sync
echo "MAGLEV_VM_EXIT=$rc"
poweroff -f
INIT
  chmod +x "$STAGE/init"
  (cd "$STAGE" && find . | cpio -o -H newc --quiet > "$INITRD.tmp")
  mv "$INITRD.tmp" "$INITRD"
  rm -rf "$STAGE"
  trap - EXIT
fi

# ---- per-run control dir: command, cwd, extra mounts, exit code ---------------
CTL="$(mktemp -d)"
trap 'rm -rf "$CTL"' EXIT
{
  printf 'exec'
  for a in "$@"; do printf " '%s'" "$(printf '%s' "$a" | sed "s/'/'\\\\''/g")"; done
  printf '\n'
} > "$CTL/cmd.sh"
echo "$PWD" > "$CTL/cwd"
VIRTFS=(-virtfs "local,path=$CTL,mount_tag=ctl,security_model=none"
        -virtfs "local,path=/usr,mount_tag=usr,security_model=none,readonly=on"
        -virtfs "local,path=$ROOT,mount_tag=vmroot,security_model=none,readonly=on")
: > "$CTL/mounts.sh"
i=0
for d in "${SHARES[@]}"; do
  VIRTFS+=(-virtfs "local,path=$d,mount_tag=s$i,security_model=none")
  echo "mkdir -p '$d' && mount -t 9p -o \"\$O\" s$i '$d'" >> "$CTL/mounts.sh"
  i=$((i + 1))
done

START=$(date +%s.%N)
set +e
timeout "$TIMEOUT" qemu-system-x86_64 -accel tcg -cpu "${MAGLEV_VM_CPU:-max}" -m "${MAGLEV_VM_MEM:-512M}" -smp 1 \
  -nodefaults -no-reboot -display none -monitor none -serial "file:$CTL/console.log" \
  -kernel "$KERNEL" -initrd "$INITRD" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 rdinit=/init" \
  "${VIRTFS[@]}" < /dev/null
QRC=$?
set -e
END=$(date +%s.%N)
tr -d '\r' < "$CTL/console.log" | grep -v '^MAGLEV_VM_EXIT=' || true
[ -n "$OUT" ] && cp "$CTL/console.log" "$OUT/console.log"
printf 'run-in-vm: kernel %s (%s), VM wall time %.2f s\n' "$KVER" "$(basename "$KERNEL")" \
  "$(echo "$END - $START" | bc -l 2>/dev/null || echo 0)" >&2
if [ "$QRC" -eq 124 ]; then
  echo "run-in-vm: timed out after $TIMEOUT s" >&2
  exit 124
fi
if [ ! -s "$CTL/rc" ]; then
  echo "run-in-vm: the guest reported no exit code (qemu rc $QRC): VM did not boot or crashed" >&2
  exit 125
fi
exit "$(cat "$CTL/rc")"
