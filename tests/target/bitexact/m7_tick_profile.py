#!/usr/bin/python3
"""Per-tick Cortex-M7 instruction counts by function, from a QEMU block log (issue 16).

m7_function_profile.py averages over the whole run. This one splits the run at
every entry of the tick function (by default Controller<float>::step), so a
tick's cost can be read function by function: which work makes the largest
Ready ticks larger than the median one (that is how the circle reference's
libgcc conversions were found, docs/PERFORMANCE.md "On-target").

  qemu-system-arm -M mps2-an500 -nographic -monitor none -serial null \\
      -semihosting-config enable=on,target=native \\
      -kernel build/qemu-m7/firmware/board/mps2_an500/kernel_replay/maglev-qemu-kernel-replay.elf \\
      -append "VECTORS.bin /tmp/out.bin" -d in_asm,exec,nochain -D /tmp/m7trace.log
  /usr/bin/python3 tests/target/bitexact/m7_tick_profile.py /tmp/m7trace.log \\
      build/qemu-m7/firmware/board/mps2_an500/kernel_replay/maglev-qemu-kernel-replay.elf \\
      [--symbol _ZN6maglev6kernel10ControllerIfE4stepE] [--last 4999] [--top 5]

An interval runs from one entry of the tick function to the next, so it also
holds what the harness does between calls (decode/encode, the icount
bookkeeping, command() between ticks): those functions are listed apart and
left out of the kernel totals; library functions (memset, memcpy) count
whoever calls them, the harness included. --last N keeps the last N complete intervals
(the replay's Ready ticks are its last 4 999). Printed: the kernel's mean per
tick by function, then the --top largest intervals with the functions that
exceed the median interval's.

  --lines SUBSTRING  the kernel's mean per tick by source line (addr2line, each
                     instruction at its own line) in the functions whose name
                     holds SUBSTRING: where inside a function the instructions go.
  --loops            per kernel function, the instructions of blocks that run
                     three or more times a tick: loops GCC left rolled (the
                     eighth session of 2026-11-27 found the axis loops' spilled
                     induction pointers this way).
  --classes          the kernel's mean per tick by instruction class (integer
                     ALU, integer load/store, branch/IT, FP arithmetic, FP
                     load/store/move, FP conversion, FP compare; mnemonics from
                     objdump), in total and for the largest functions: how much
                     of a tick is arithmetic and how much is bookkeeping.
  --step-only        count only the blocks run inside the tick function (from
                     its entry to the next harness block), not command() and
                     what it calls between ticks: then an interval is what the
                     icount replay measures.
  --kinds            (implies --step-only) min / median / max per tick by the
                     reference work it did (circle, move, sinusoid, excitation,
                     quiet): which ticks set the replay's maximum.
"""
import argparse
import collections
import subprocess
import sys

HARNESS = ('kernel_replay', '_Z6replay', 'TickStats', 'semihost', 'icount')


def entry_address(elf, symbol):
    out = subprocess.run(['arm-none-eabi-nm', elf], capture_output=True, text=True, check=True).stdout
    hits = [line.split()[0] for line in out.splitlines() if symbol in line and line.split()[1] in 'TtWw']
    if len(hits) != 1:
        sys.exit('m7_tick_profile: %d symbols match %r in %s (need exactly one)' % (len(hits), symbol, elf))
    return int(hits[0], 16)


def intervals(log, entry, step_only=False):
    ninsn = {}
    insns = {}  # block start -> the addresses of its instructions
    fn_of = {}
    ticks = []
    cur = collections.Counter()
    cur_pc = None
    cur_n = 0
    inside = False
    with open(log, 'r', errors='replace') as f:
        for line in f:
            if line.startswith('Trace 0:'):
                i = line.index('[')
                pc = int(line[i + 1:line.index(']')].split('/')[1], 16)
                if pc == entry:
                    ticks.append(cur)
                    cur = collections.Counter()
                    inside = True
                fn = fn_of.setdefault(pc, line[line.index(']') + 2:].strip())
                if step_only and any(h in fn for h in HARNESS):
                    inside = False  # back in the harness: step() has returned
                if inside or not step_only:
                    cur[pc] += 1
            elif line.startswith('0x'):
                if cur_pc is None:
                    cur_pc = int(line[2:10], 16)
                    cur_n = 0
                    cur_insns = []
                cur_n += 1
                cur_insns.append(int(line[2:10], 16))
            elif line.startswith('IN:') or line.strip() == '' or line.startswith('----'):
                if cur_pc is not None:
                    ninsn[cur_pc] = cur_n
                    insns[cur_pc] = cur_insns
                    cur_pc = None
    # ticks[0] is everything before the first entry; the open one after the
    # last entry runs to the end of the program: drop both.
    out = []
    for c in ticks[1:]:
        by_fn = collections.Counter()
        for pc, n in c.items():
            by_fn[fn_of[pc]] += n * ninsn.get(pc, 0)
        out.append(by_fn)
    return out, [c for c in ticks[1:]], ninsn, insns, fn_of


CLASSES = ('int-alu', 'int-ldst', 'branch/it', 'fp-arith', 'fp-ldst/move', 'fp-convert', 'fp-compare')


def instruction_class(mnemonic):
    base = mnemonic.split('.')[0]
    if base.startswith('v'):
        if base in ('vldr', 'vstr', 'vldmia', 'vstmia', 'vldmdb', 'vstmdb', 'vpush', 'vpop', 'vmov'):
            return 'fp-ldst/move'
        if base.startswith(('vcvt', 'vrint')):
            return 'fp-convert'
        if base in ('vcmp', 'vcmpe', 'vmrs'):
            return 'fp-compare'
        return 'fp-arith'
    if base.startswith(('ldr', 'str', 'ldm', 'stm', 'push', 'pop')):
        return 'int-ldst'
    if base.startswith(('b', 'cb', 'it', 'tb')) and base not in ('bic', 'bics', 'bfi', 'bfc'):
        return 'branch/it'
    return 'int-alu'


def mnemonics(elf):
    """address -> mnemonic of every instruction in the ELF (one objdump call)."""
    out = subprocess.run(['arm-none-eabi-objdump', '-d', '--no-show-raw-insn', elf],
                         capture_output=True, text=True, check=True).stdout
    m = {}
    for line in out.splitlines():
        parts = line.split('\t')
        if len(parts) >= 2 and parts[0].strip().endswith(':'):
            try:
                m[int(parts[0].strip()[:-1], 16)] = parts[1].strip().split()[0]
            except (ValueError, IndexError):
                pass
    return m


def source_lines(elf, pcs):
    """pc -> 'file:line' (the innermost inlined frame's), one addr2line call."""
    if not pcs:
        return {}
    res = subprocess.run(['arm-none-eabi-addr2line', '-e', elf] + ['0x%x' % pc for pc in pcs],
                         capture_output=True, text=True, check=True).stdout.splitlines()
    return {pc: line.rsplit('/', 1)[-1].split(' ')[0] for pc, line in zip(pcs, res)}


def kernel(by_fn):
    return {f: v for f, v in by_fn.items() if not any(h in f for h in HARNESS)}


# A tick's kind: the reference generator or excitation it ran (the ticks that
# set the replay's maximum are a kind, not noise).
TICK_KINDS = (('circle', 'CircleReference'), ('move', 'MoveReference'), ('sinusoid', 'SinusoidReference'),
              ('excitation', 'excite'))


def tick_kind(by_fn):
    for name, sub in TICK_KINDS:
        if any(sub in f and v >= 20 for f, v in kernel(by_fn).items()):
            return name
    return 'quiet'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('log')
    ap.add_argument('elf')
    ap.add_argument('--symbol', default='_ZN6maglev6kernel10ControllerIfE4stepE')
    ap.add_argument('--last', type=int, default=0, help='keep the last N intervals (0: all)')
    ap.add_argument('--top', type=int, default=5)
    ap.add_argument('--lines', default='', help='per source line in the functions whose name holds this')
    ap.add_argument('--loops', action='store_true', help='blocks run three or more times a tick, by function')
    ap.add_argument('--classes', action='store_true', help='mean per tick by instruction class')
    ap.add_argument('--step-only', action='store_true',
                    help='count only what runs inside the tick function (not command() between ticks)')
    ap.add_argument('--kinds', action='store_true',
                    help='(implies --step-only) min / median / max per tick by the reference work it did')
    ap.add_argument('--only-kind', default='',
                    help='(implies --step-only) keep only the ticks of this kind (see --kinds): circle, move, ...')
    a = ap.parse_args()
    ticks, blocks, ninsn, insns, fn_of = intervals(a.log, entry_address(a.elf, a.symbol),
                                                  a.step_only or a.kinds or bool(a.only_kind))
    if a.last > 0:
        ticks = ticks[-a.last:]
        blocks = blocks[-a.last:]
    if a.only_kind:
        keep = [k for k, b in enumerate(ticks) if tick_kind(b) == a.only_kind]
        ticks = [ticks[k] for k in keep]
        blocks = [blocks[k] for k in keep]
    if not ticks:
        sys.exit('m7_tick_profile: no complete interval (is --symbol the tick function?)')


    totals = [(sum(kernel(b).values()), k, b) for k, b in enumerate(ticks)]
    order = sorted(totals, key=lambda t: t[0])
    median = order[len(order) // 2]
    n = len(ticks)
    mean = collections.Counter()
    for _, _, b in totals:
        for f, v in kernel(b).items():
            mean[f] += v
    print('%d intervals; kernel instructions per interval: min %d, median %d, max %d, mean %.1f' %
          (n, order[0][0], median[0], order[-1][0], sum(mean.values()) / n))
    for f, v in mean.most_common(30):
        print('%9.1f  %s' % (v / n, f))
    for total, k, b in order[::-1][:a.top]:
        print('interval %d (of the kept ones): %d, median %d' % (k, total, median[0]))
        kb, km = kernel(b), kernel(median[2])
        diffs = sorted(((kb.get(f, 0) - km.get(f, 0), f) for f in set(kb) | set(km)), reverse=True)
        for d, f in diffs:
            if d >= 10:
                print('   %+6d  %s' % (d, f))
    per_pc = collections.Counter()
    for c in blocks:
        per_pc.update(c)
    if a.lines:
        # Each instruction counts at its own source line (a block's
        # instructions often come from several lines and inlined functions).
        pcs = sorted(pc for pc in per_pc if a.lines in fn_of[pc])
        where = source_lines(a.elf, sorted({i for pc in pcs for i in insns.get(pc, [pc])}))
        by_line = collections.Counter()
        for pc in pcs:
            for i in insns.get(pc, [pc]):
                by_line[where[i]] += per_pc[pc] / n
        print('by source line, functions holding %r (mean per tick):' % a.lines)
        for line, v in sorted(by_line.items(), key=lambda kv: -kv[1]):
            if v >= 0.5:
                print('%9.1f  %s' % (v, line))
    if a.loops:
        rolled = collections.Counter()
        for pc, cnt in per_pc.items():
            f = fn_of[pc]
            if cnt / n >= 3 and not any(h in f for h in HARNESS):
                rolled[f] += cnt * ninsn.get(pc, 0) / n
        print('instructions per tick in blocks run three or more times a tick (rolled loops):')
        for f, v in rolled.most_common():
            print('%9.1f  %s' % (v, f))
    if a.classes:
        mn = mnemonics(a.elf)
        by_class = collections.Counter()
        per_fn = collections.defaultdict(collections.Counter)
        for pc, cnt in per_pc.items():
            f = fn_of[pc]
            if any(h in f for h in HARNESS):
                continue
            for i in insns.get(pc, [pc]):
                c = instruction_class(mn.get(i, '?'))
                by_class[c] += cnt / n
                per_fn[f][c] += cnt / n
        print('kernel instructions per tick by class (mean):')
        for c in CLASSES:
            print('%9.1f  %s' % (by_class[c], c))
        print('%9.1f  all' % sum(by_class.values()))
        print('%-60s' % 'largest functions' + ''.join('%13s' % c for c in CLASSES))
        for f, c in sorted(per_fn.items(), key=lambda kv: -sum(kv[1].values()))[:12]:
            print('%-60s' % f[:60] + ''.join('%13.1f' % c[k] for k in CLASSES))
    if a.kinds:
        # A tick's kind: the reference generator or excitation it ran (the
        # ticks that set the replay's maximum are a kind, not noise).
        by_kind = collections.defaultdict(list)
        for tick_total, _, b in totals:
            by_kind[tick_kind(b)].append(tick_total)
        print('%-12s %6s %8s %8s %8s' % ('tick kind', 'ticks', 'min', 'median', 'max'))
        for kind, v in sorted(by_kind.items(), key=lambda kv: max(kv[1])):
            v.sort()
            print('%-12s %6d %8d %8d %8d' % (kind, len(v), v[0], v[len(v) // 2], v[-1]))


if __name__ == '__main__':
    main()
