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

With --calibrate, a third controller: ours after the kernel's own coupling
calibration on the same stage (`run --calibrate`, issue 15 item 5), as a lab
runs it on a new stage. Which controller is better is decided by
hil/report/ranking.py: a CCQ at the bench's noise (below 2x its rest-noise
CCQ) for both is a tie, and so are two medians whose ranges over the seeds
overlap; only the rest are ranked, with the ratio ours / printed.

  usage: preset_comparison.py MAGLEV_HIL SCENARIO_DIR OUT_DIR [--seeds N] [--calibrate] [--markdown FILE] [--reuse]
"""
import json
import os
import re
import statistics
import subprocess
import sys

import ranking


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


def run(hil, scenario_file, out, seed, reuse=False, calibrate=False):
    path = os.path.join(out, 'metrics.json')
    if reuse and os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    cmd = [hil, 'run', scenario_file, '--out', out, '--plant', 'as-built', '--error-seed', str(seed),
           '--no-plots', '--quiet']
    if calibrate:
        # Our controller as a lab runs it on a new stage: the kernel's own
        # coupling calibration first (a session on the same stage), then the
        # scenario with the correction it kept (docs/BENCH.md --calibrate).
        cmd.append('--calibrate')
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


CONTROLLERS = (('default', 'ours (default)'), ('calibrated', 'ours, calibrated'), ('paper', 'printed PIDs'))


def verdict(r, ctl):
    """Ours (ctl) against the printed PIDs on one figure, in words."""
    v = ranking.rank(r['figure'], r[ctl], r['paper'], r.get(ctl + '_rest'), r.get('paper_rest'))
    return {'a': 'ours', 'b': 'printed'}.get(v, v)


def main(argv):
    if len(argv) < 4:
        print(__doc__)
        return 2
    hil, scen_dir, out_dir = argv[1], argv[2], argv[3]
    seeds = int(argv[argv.index('--seeds') + 1]) if '--seeds' in argv else 3
    markdown = argv[argv.index('--markdown') + 1] if '--markdown' in argv else None
    reuse = '--reuse' in argv  # keep runs already in OUT_DIR (same binary, same seeds)
    calibrate = '--calibrate' in argv
    controllers = [c for c in CONTROLLERS if calibrate or c[0] != 'calibrated']
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
        results = {c: [] for c, _ in controllers}
        for seed in range(1, seeds + 1):
            for ctl, _ in controllers:
                scenario = paper_file if ctl == 'paper' else os.path.join(scen_dir, fname)
                results[ctl].append(run(hil, scenario, os.path.join(out_dir, name, ctl, str(seed)), seed, reuse,
                                        calibrate=(ctl == 'calibrated')))
        for key, paper in figures.items():
            row = {'scenario': name, 'figure': key, 'paper_value': paper}
            for ctl, _ in controllers:
                vals = [m.get(key) if m else None for m in results[ctl]]
                faulted = sum(1 for m in results[ctl] if m is None or m.get('fault_code', 0) != 0)
                row[ctl] = median_span(vals)
                row[ctl + '_faulted'] = faulted
                if ranking.is_ccq(key):
                    rest = [m.get(ranking.rest_noise_key(key)) if m else None for m in results[ctl]]
                    row[ctl + '_rest'] = median_span(rest)[0]
            row['better'] = verdict(row, 'default')
            if calibrate:
                row['better_calibrated'] = verdict(row, 'calibrated')
            rows.append(row)
    head = '| scenario | figure | paper |'
    rule = '|---|---|---|'
    for ctl, title in controllers:
        head += ' %s median [min, max] | / paper |' % title
        rule += '---|---|'
    head += ' ours (default) vs printed | ours / printed |'
    rule += '---|---|'
    if calibrate:
        head += ' ours, calibrated, vs printed | calibrated / printed |'
        rule += '---|---|'
    lines = [head, rule]

    def cell(r, ctl):
        m, lo, hi = r[ctl]
        if m is None:
            return 'n/a', 'n/a'
        extra = ' (%d of %d runs faulted)' % (r[ctl + '_faulted'], seeds) if r[ctl + '_faulted'] else ''
        return '%.4g [%.4g, %.4g]%s' % (m, lo, hi, extra), '%.3g' % (m / r['paper_value']) if r['paper_value'] else '-'

    def versus(r, ctl):
        a, b = r[ctl][0], r['paper'][0]
        return '%.3g' % (a / b) if a is not None and b else '-'

    for r in rows:
        line = '| %s | %s | %.4g |' % (r['scenario'], r['figure'], r['paper_value'])
        for ctl, _ in controllers:
            c, ratio = cell(r, ctl)
            line += ' %s | %s |' % (c, ratio)
        line += ' %s | %s |' % (r['better'], versus(r, 'default'))
        if calibrate:
            line += ' %s | %s |' % (r['better_calibrated'], versus(r, 'calibrated'))
        lines.append(line)

    def tally(field, who):
        counts = {}
        for r in rows:
            counts[r[field]] = counts.get(r[field], 0) + 1
        order = ('ours', 'printed', 'equal', 'tie: noise', 'tie: spread', '-')
        parts = ['%s %d' % ({'-': 'not ranked'}.get(k, k), counts.get(k, 0)) for k in order]
        return '%s against the printed PIDs, %d figures: %s' % (who, len(rows), ', '.join(parts))

    lines.append('')
    lines.append(tally('better', 'ours (default)') + ' (as-built, error seeds 1-%d)' % seeds)
    if calibrate:
        lines.append(tally('better_calibrated', 'ours, calibrated') + ' (as-built, error seeds 1-%d)' % seeds)
    lines.append('(ranking: hil/report/ranking.py -- a CCQ below %gx its rest-noise CCQ is noise, and two '
                 'medians whose [min, max] ranges overlap are a tie)' % ranking.NOISE_FACTOR)
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
