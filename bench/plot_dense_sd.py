#!/usr/bin/python3
"""Chart the dense-SD benchmark (bench_dense_sd): time of one FTS solve (prepare + solve) against N
on 1 and 2 threads, before and after the LAPACK path, and the phases (far-field assembly, near
field, factorisation, solve) of the new path.

usage: plot_dense_sd.py [AFTER.json] [BEFORE.json] [OUT.png]
  defaults: bench/results/dense_sd.json, bench/results/dense_sd_before.json (skipped if absent),
            bench/results/dense_sd.png; AFTER with "_passive" before ".json" (the same driver run
            with OMP_WAIT_POLICY=passive) is drawn too when it exists
"""
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

after_src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/dense_sd.json"
before_src = sys.argv[2] if len(sys.argv) > 2 else "bench/results/dense_sd_before.json"
out = sys.argv[3] if len(sys.argv) > 3 else "bench/results/dense_sd.png"
PHASES = ["assembly", "near_field", "factorisation", "solve"]


def load(path):
    if not os.path.exists(path):
        return {}
    table = {}
    for r in json.load(open(path))["rows"]:
        table[(int(r["params"]["N"]), int(r["params"]["threads"]))] = r["phases"]
    return table


after, before = load(after_src), load(before_src)
passive = load(after_src.replace(".json", "_passive.json"))
fig, axes = plt.subplots(1, 2, figsize=(13, 5))
ax = axes[0]
for table, label, style in ((before, "before (Eigen LLT + inverse)", "--"), (after, "LAPACK path", "-"),
                            (passive, "LAPACK path, OMP_WAIT_POLICY=passive", ":")):
    for threads, marker in ((1, "o"), (2, "s")):
        ns = sorted(n for (n, t) in table if t == threads)
        if ns:
            ax.loglog(ns, [table[(n, threads)]["total"] for n in ns], style, marker=marker,
                      label=f"{label}, {threads} thread{'s' if threads > 1 else ''}")
for (n, t), ph in sorted(after.items()):
    b = before.get((n, t))
    print(f"N={n:5d} threads={t}: total {ph['total']:.3e} s (assembly {ph['assembly']:.2e}, near field "
          f"{ph['near_field']:.2e}, factorisation {ph['factorisation']:.2e}, solve {ph['solve']:.2e})"
          + (f"; before {b['total']:.3e} s, speed-up {b['total'] / ph['total']:.1f}x" if b else ""))
ax.plot([400], [0.5], "k*", ms=12, label="goal: 0.5 s at N = 400")
ax.set_xlabel("N (spheres)")
ax.set_ylabel("prepare + solve (s)")
ax.set_title("Dense SD, one FTS mobility solve, open domain")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)

ax = axes[1]
ns = sorted({n for (n, t) in after})
x = np.arange(len(ns))
width = 0.38
for k, threads in enumerate((1, 2)):
    bottom = np.zeros(len(ns))
    for p_i, p in enumerate(PHASES):
        vals = np.array([after.get((n, threads), {}).get(p, 0.0) for n in ns])
        ax.bar(x + (k - 0.5) * width, vals, width, bottom=bottom, color=f"C{p_i}",
               label=p if k == 0 else None, hatch="//" if threads == 2 else None, edgecolor="white")
        bottom += vals
ax.set_yscale("log")
ax.set_xticks(x)
ax.set_xticklabels([f"N={n}\n1 | 2 thr" for n in ns])
ax.set_ylabel("seconds (stacked phases)")
ax.set_title("LAPACK path: phases (left bar 1 thread, hatched 2 threads)")
ax.legend(fontsize=8)
fig.tight_layout()
os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
fig.savefig(out, dpi=110)
print(f"wrote {out}")
