#!/bin/sh
# check-no-heap.sh <nm> <elf>
#
# Fails (exit 1) if the linked firmware image contains any heap or C++
# exception machinery. Firmware must be heap-free and exception-free; gc'd
# links keep only what something references, so a symbol below appearing in
# the final ELF means some code path can allocate or throw.
# Prints every offending symbol (demangled) with its address and type.
set -eu
if [ $# -ne 2 ]; then
  echo "usage: $0 <nm> <elf>" >&2
  exit 2
fi
nm_tool=$1
elf=$2
if [ ! -f "$elf" ]; then
  echo "check-no-heap: no such file: $elf" >&2
  exit 2
fi

# Symbol name = everything after "<addr> <type> " (demangled names have spaces).
# Undefined symbols (no address) are listed too: a final ELF should have none.
found=$("$nm_tool" -C "$elf" | awk '
  { if (NF >= 3) { name = $0; sub(/^[0-9a-fA-F]+ [A-Za-z] /, "", name) }
    else         { name = $0; sub(/^ *[A-Za-z] /, "", name) } }
  name ~ /^(malloc|_malloc_r|free|_free_r|calloc|_calloc_r|realloc|_realloc_r|memalign|_memalign_r|_sbrk|_sbrk_r)$/ ||
  name ~ /^operator (new|delete)(\[\])?\(/ ||
  name ~ /^__cxa_(throw|rethrow|allocate_exception|begin_catch|end_catch)$/ ||
  name ~ /^__gxx_personality_v0$/ ||
  name ~ /^_Unwind_/ { print "  " $0 }')

if [ -n "$found" ]; then
  echo "check-no-heap: FAIL: $elf links heap/exception symbols:"
  echo "$found"
  exit 1
fi
echo "check-no-heap: OK: $elf has no heap or exception symbols"
exit 0
