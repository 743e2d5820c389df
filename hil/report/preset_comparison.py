#!/usr/bin/env python3
"""Paper 000's printed controller against our defaults, on the as-built stage (issue 15, item 4).

For every scenario with a [paper] section: the scenario as shipped (our
defaults) and the same scenario with `[controller] preset = paper` (the PIDs
(27), (28), (32), (33) on the error, no shaping of ours; docs/BENCH.md), each
on the as-built plant over error seeds 1..N. Per paper figure: the paper's
value, each controller's median [min, max] and their ratio to the paper, and
which controller is better by the figure's own sense (lower is better for
noise, overshoot, settling, CCQ; higher for crossover, margin, bandwidth).
Nothing is fitted; both controllers see the same drawn errors and noise.

  usage: preset_comparison.py MAGLEV_HIL SCENARIO_DIR OUT_DIR [--seeds N] [--markdown FILE] [--reuse]
"""
import json
import os
import re
import statistics
import subprocess
import sys


def paper_figures(text):
    figures, section = {}, None
    for raw in text.splitlines():
        line = raw.split('#', 1)[0].strip()
        if not line:
            continue
        if line.startswith('['):
            section = line.strip('[]').strip()
            continue
        if section == 'paper' and '=' in line:
            k, v = (s.strip() for s in line.split('=', 1))
            figures[k] = float(v)
    return figures


def with_paper_preset(text, name):
    text = re.sub(r'^name\s*=.*$', 'name = ' + name, text, count=1, flags=re.M)
    if re.search(r'^\[controller\]\s*$', text, flags=re.M):
        return re.sub(r'^\[controller\]\s*$', '[controller]\npreset = paper', text, count=1, flags=re.M)
    return re.sub(r'^\[timeline\]\s*$', '[controller]\npreset = paper\n\n[timeline]', text, count=1, flags=re.M)


def higher_is_better(key):
    return any(s in key for s in ('crossover', 'phase_margin', 'bandwidth'))


def neutral(key):
    # Closeness to the paper, not better or worse: the closed-loop peak.
    return 'peak_dB' in key


def run(hil, scenario_file, out, seed, reuse=False):
    path = os.path.join(out, 'metrics.json')
    if reuse and os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    cmd = [hil, 'run', scenario_file, '--out', out, '--plant', 'as-built', '--error-seed', str(seed),
           '--no-plots', '--quiet']
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def median_span(values):
    v = [x for x in values if x is not None]
    if not v:
        return None, None, None
    return statistics.median(v), min(v), max(v)


def main(argv):
    if len(argv) < 4:
        print(__doc__)
        return 2
    hil, scen_dir, out_dir = argv[1], argv[2], argv[3]
    seeds = int(argv[argv.index('--seeds') + 1]) if '--seeds' in argv else 3
    markdown = argv[argv.index('--markdown') + 1] if '--markdown' in argv else None
    reuse = '--reuse' in argv  # keep runs already in OUT_DIR (same binary, same seeds)
    os.makedirs(out_dir, exist_ok=True)
    rows = []
    for fname in sorted(os.listdir(scen_dir)):
        if not fname.endswith('.scenario'):
            continue
        with open(os.path.join(scen_dir, fname)) as f:
            text = f.read()
        figures = paper_figures(text)
        if not figures:
            continue
        name = fname[:-len('.scenario')]
        paper_file = os.path.join(out_dir, name + '_paper_preset.scenario')
        with open(paper_file, 'w') as f:
            f.write(with_paper_preset(text, name + '_paper_preset'))
        results = {'default': [], 'paper': []}
        for seed in range(1, seeds + 1):
            results['default'].append(run(hil, os.path.join(scen_dir, fname),
                                          os.path.join(out_dir, name, 'default', str(seed)), seed, reuse))
            results['paper'].append(run(hil, paper_file, os.path.join(out_dir, name, 'paper', str(seed)), seed, reuse))
        for key, paper in figures.items():
            row = {'scenario': name, 'figure': key, 'paper_value': paper}
            for ctl in ('default', 'paper'):
                vals = [m.get(key) if m else None for m in results[ctl]]
                faulted = sum(1 for m in results[ctl] if m is None or m.get('fault_code', 0) != 0)
                row[ctl] = median_span(vals)
                row[ctl + '_faulted'] = faulted
            d, p = row['default'][0], row['paper'][0]
            if d is None or p is None or neutral(key):
                row['better'] = '-'
            elif d == p:
                row['better'] = 'equal'
            else:
                ours = (d > p) if higher_is_better(key) else (d < p)
                row['better'] = 'ours' if ours else 'paper'
            rows.append(row)
    lines = ['| scenario | figure | paper | ours (default) median [min, max] | ours / paper | printed PIDs median [min, max] '
             '| printed / paper | better |', '|---|---|---|---|---|---|---|---|']
    for r in rows:
        def cell(ctl):
            m, lo, hi = r[ctl]
            if m is None:
                return 'n/a', 'n/a'
            extra = ' (%d of %d runs faulted)' % (r[ctl + '_faulted'], seeds) if r[ctl + '_faulted'] else ''
            return '%.4g [%.4g, %.4g]%s' % (m, lo, hi, extra), '%.3g' % (m / r['paper_value']) if r['paper_value'] else '-'
        dc, dr = cell('default')
        pc, pr = cell('paper')
        lines.append('| %s | %s | %.4g | %s | %s | %s | %s | %s |' % (r['scenario'], r['figure'], r['paper_value'], dc, dr,
                                                                     pc, pr, r['better']))
    ours = sum(1 for r in rows if r['better'] == 'ours')
    theirs = sum(1 for r in rows if r['better'] == 'paper')
    equal = sum(1 for r in rows if r['better'] == 'equal')
    lines.append('')
    lines.append('%d figures: ours better on %d, the printed PIDs on %d, equal on %d, not ranked %d '
                 '(as-built, error seeds 1-%d)' % (len(rows), ours, theirs, equal, len(rows) - ours - theirs - equal,
                                                    seeds))
    text = '\n'.join(lines) + '\n'
    print(text)
    if markdown:
        with open(markdown, 'w') as f:
            f.write(text)
    with open(os.path.join(out_dir, 'preset_comparison.json'), 'w') as f:
        json.dump(rows, f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
