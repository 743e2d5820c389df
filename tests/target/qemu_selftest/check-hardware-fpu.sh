#!/bin/sh
# check-hardware-fpu.sh <objdump> <elf>
# The FPU self test only proves something if the arithmetic runs on the FPv5
# unit: require the VFP instructions it exercises, and no soft-float helpers.
set -u
objdump=$1; elf=$2
listing=$("$objdump" -d "$elf") || exit 2
status=0
for insn in vadd.f32 vmul.f32 vdiv.f32 vsqrt.f32 vfma.f32 vdiv.f64 vsqrt.f64 vcvt.f32.s32; do
  count=$(printf '%s\n' "$listing" | grep -c "	$insn")
  echo "$insn: $count"
  [ "$count" -gt 0 ] || { echo "missing $insn" >&2; status=1; }
done
if printf '%s\n' "$listing" | grep -E -q '<__aeabi_(f|d)(add|sub|mul|div)>:'; then
  echo "soft-float helpers linked" >&2
  status=1
fi
exit $status
