#!/usr/bin/python3
"""Compare two `maglev-hil suite --out DIR` results metric by metric.

    compare_suites.py BEFORE_DIR AFTER_DIR [--paper-only] [--markdown FILE]

For every scenario in both directories, every numeric key of metrics.json
(less the wall-clock and CPU-time keys) is compared: before, after, relative
change. --paper-only keeps the keys the scenario's [paper] section judges
(the suite's verdict rows), read from hil/scenarios/NAME.scenario. Prints
the largest relative changes first and a summary line; exits 0 (a report,
not a test). Used for the integrator change of issue 16 item 5
(docs/PERFORMANCE.md "Bench speed").
"""
import json
import os
import sys

SKIP = ("wall", "real_time", "cpu_s", "cpu_time", "bus_load")


def paper_keys(scenario_dir, name):
    path = os.path.join(scenario_dir, name + ".scenario")
    keys = set()
    if not os.path.exists(path):
        return keys
    section = None
    for line in open(path):
        s = line.split("#", 1)[0].strip()
        if s.startswith("[") and s.endswith("]"):
            section = s[1:-1]
        elif section == "paper" and "=" in s:
            keys.add(s.split("=", 1)[0].strip())
    return keys


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    paper_only = "--paper-only" in sys.argv
    md = None
    if "--markdown" in sys.argv:
        md = sys.argv[sys.argv.index("--markdown") + 1]
        args.remove(md)
    before, after = args[0], args[1]
    here = os.path.dirname(os.path.abspath(__file__))
    scen_dir = os.path.join(here, "..", "scenarios")
    rows = []
    for name in sorted(os.listdir(before)):
        fb = os.path.join(before, name, "metrics.json")
        fa = os.path.join(after, name, "metrics.json")
        if not (os.path.exists(fb) and os.path.exists(fa)):
            continue
        mb, ma = json.load(open(fb)), json.load(open(fa))
        pk = paper_keys(scen_dir, name)
        for k, vb in mb.items():
            if any(s in k for s in SKIP) or k not in ma:
                continue
            va = ma[k]
            if isinstance(vb, bool) or not isinstance(vb, (int, float)) or not isinstance(va, (int, float)):
                continue
            if paper_only and k not in pk:
                continue
            rel = 0.0 if vb == va else (abs(va - vb) / abs(vb) if vb != 0 else float("inf"))
            rows.append((rel, name, k, vb, va, k in pk))
    rows.sort(key=lambda r: -r[0])
    lines = ["| scenario | metric | before | after | change |", "|---|---|---|---|---|"]
    for rel, name, k, vb, va, is_paper in rows:
        lines.append("| %s | %s%s | %.6g | %.6g | %s |" % (name, k, " (paper)" if is_paper else "", vb, va,
                                                         "%.2f %%" % (100 * rel) if rel != float("inf") else "from 0"))
    n_changed = sum(1 for r in rows if r[0] > 0)
    worst = rows[0] if rows else None
    summary = "%d metrics compared, %d changed; largest change %s" % (
        len(rows), n_changed, "%.2f %% (%s %s)" % (100 * worst[0], worst[1], worst[2]) if worst else "-")
    print(summary)
    for line in lines[:60 if not paper_only else len(lines)]:
        print(line)
    if md:
        with open(md, "w") as f:
            f.write(summary + "\n\n" + "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
