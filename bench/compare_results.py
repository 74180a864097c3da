#!/usr/bin/python3
"""Compare two sets of benchmark results phase by phase: the median over repeated runs of each
(benchmark, parameters, phase) in NEW divided by the same in OLD, summarised per benchmark and
phase (median, range, worst row). Timings below 0.2 ms are left out (timer noise). Use it to check
that a change does not slow the hot paths: run the same drivers of both builds alternately on one
machine, e.g. three rounds of `bench_<name> --quick --out DIR/rK`.

usage: compare_results.py OLD_DIR NEW_DIR   (each holding r*/<benchmark>.json or <benchmark>.json)
"""
import glob
import json
import os
import statistics
import sys


def load(root):
    rows = {}
    for f in glob.glob(os.path.join(root, "**", "*.json"), recursive=True):
        name = os.path.basename(f)[:-5]
        for r in json.load(open(f))["rows"]:
            key = (name, tuple(sorted(r["params"].items())))
            for phase, t in r["phases"].items():
                if isinstance(t, (int, float)) and t > 0:
                    rows.setdefault((key, phase), []).append(t)
    return rows


old, new = load(sys.argv[1]), load(sys.argv[2])
summary = {}
for k in sorted(set(old) & set(new)):
    (name, params), phase = k
    o, n = statistics.median(old[k]), statistics.median(new[k])
    if o < 2e-4:
        continue
    summary.setdefault((name, phase), []).append((n / o, dict(params), o, n))
for (name, phase), v in sorted(summary.items()):
    r = [x[0] for x in v]
    w = max(v, key=lambda x: x[0])
    print(f"{name:24s} {phase:15s} rows {len(v):3d}  median new/old {statistics.median(r):.3f}  "
          f"range {min(r):.2f}-{max(r):.2f}  worst {w[2]:.3e} -> {w[3]:.3e} s at {w[1]}")
