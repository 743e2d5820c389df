#!/bin/sh
# check-no-libm.sh <nm> <elf>
#
# Fails (exit 1) if the linked firmware image contains libm's transcendental
# functions (sin, cos, tan, atan, atan2, exp, log, pow, hypot and their float
# forms or internals). The kernel's results must not depend on which libm it
# was linked with: it uses its own deterministic functions
# (maglev/numeric/elementary.hpp), so the host and the Cortex-M7 agree bit for
# bit by construction. sqrt stays: IEEE 754 defines it exactly.
set -eu
if [ $# -ne 2 ]; then
  echo "usage: $0 <nm> <elf>" >&2
  exit 2
fi
found=$("$1" "$2" | awk '{ print $NF }' | grep -xE '(sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|exp|exp2|expm1|log|log2|log10|log1p|pow|hypot|cbrt)f?|__ieee754_(rem_pio2|exp|log|pow|atan2|hypot)f?|__kernel_(sin|cos|tan|rem_pio2)f?' || true)
if [ -n "$found" ]; then
  echo "check-no-libm: FAIL: $2 links libm transcendental functions:"
  echo "$found" | sed 's/^/  /'
  exit 1
fi
echo "check-no-libm: OK: $2 uses no libm transcendental function"
exit 0
