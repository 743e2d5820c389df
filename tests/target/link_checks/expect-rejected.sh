#!/bin/sh
# expect-rejected.sh <check-no-heap.sh> <nm> <bad.elf>
# Passes only if the checker exits 1 AND reports malloc, free, operator new,
# operator delete and _sbrk (the symbols control_bad.cpp drags in).
set -u
checker=$1; nm_tool=$2; elf=$3
output=$(sh "$checker" "$nm_tool" "$elf" 2>&1)
status=$?
echo "$output"
if [ "$status" -ne 1 ]; then
  echo "expect-rejected: checker exit status $status, expected 1" >&2
  exit 1
fi
for symbol in ' malloc$' ' free$' ' _sbrk$' ' operator new(' ' operator delete('; do
  if ! printf '%s\n' "$output" | grep -q -- "$symbol"; then
    echo "expect-rejected: checker did not report '$symbol'" >&2
    exit 1
  fi
done
echo "expect-rejected: OK, the checker rejected $elf"
