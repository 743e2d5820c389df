#!/usr/bin/python3
"""Per-function Cortex-M7 instruction counts of a QEMU run (issue 16).

QEMU has no profiler for the guest, but its TCG log names every translation
block it runs: with `-d in_asm,exec,nochain` each executed block is logged
("Trace 0: ... [flags/PC/...] function"), and each translated block with its
instructions ("IN:" followed by one line per instruction). Executions x
instructions per block, summed by function, divided by the ticks replayed:

  qemu-system-arm -M mps2-an500 -nographic -monitor none -serial null \
      -semihosting-config enable=on,target=native \
      -kernel build/qemu-m7/firmware/board/mps2_an500/kernel_replay/maglev-qemu-kernel-replay.elf \
      -append "VECTORS.bin /tmp/out.bin" -d in_asm,exec,nochain -D /tmp/m7trace.log
  /usr/bin/python3 tests/target/bitexact/m7_function_profile.py /tmp/m7trace.log 11089

The log is large (~1.8 GB for the 11 089-tick replay). The figures include
the replay harness (main, encode_output, memset/memcpy of its records) and
one-off configuration work (loop-margin checks, the Hall solve), averaged
over all ticks: use them for where the tick's time goes, and the replay's
--icount figures for the per-state totals.
"""
import sys, collections, re
ninsn = {}      # pc -> instruction count of TB
execs = collections.Counter()
fn_of = {}
cur_pc = None; cur_n = 0
with open(sys.argv[1], 'r', errors='replace') as f:
    for line in f:
        if line.startswith('Trace 0:'):
            i = line.index('[')
            parts = line[i+1:line.index(']')].split('/')
            pc = int(parts[1], 16)
            execs[pc] += 1
            if pc not in fn_of:
                fn_of[pc] = line[line.index(']')+2:].strip()
        elif line.startswith('0x'):
            if cur_pc is None:
                cur_pc = int(line[2:10], 16); cur_n = 0
            cur_n += 1
        elif line.startswith('IN:') or line.strip() == '' or line.startswith('----'):
            if cur_pc is not None:
                ninsn[cur_pc] = cur_n
                cur_pc = None
byfn = collections.Counter()
total = 0
for pc, c in execs.items():
    n = ninsn.get(pc, 0)
    byfn[fn_of.get(pc, '?')] += c * n
    total += c * n
ticks = float(sys.argv[2])
print('total %d instr, %.0f per tick' % (total, total / ticks))
for fn, c in byfn.most_common(40):
    print('%10.0f  %5.1f%%  %s' % (c / ticks, 100.0 * c / total, fn))
