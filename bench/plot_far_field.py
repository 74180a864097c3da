#!/usr/bin/python3
"""Chart the direct far-field benchmark: time per time step and per mobility product against N with
the fitted exponents (log-log least squares over N >= 400, or all points for short runs), and the
2-thread speed-up; with --reference REF.json (the same benchmark with BENCH_DIRECT=reference: the
plain per-pair loop, mobility_product_reference) also the product's speed-up over it, printed as a table.

usage: plot_far_field.py [RESULTS.json] [OUT.png] [--reference REF.json]
       (defaults: bench/results/far_field_direct.json)
Uses only Debian's python3-numpy and python3-matplotlib.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

args = sys.argv[1:]
ref_rows = None
if "--reference" in args:
    k = args.index("--reference")
    ref_rows = json.load(open(args[k + 1]))["rows"]
    del args[k:k + 2]
src = args[0] if len(args) > 0 else "bench/results/far_field_direct.json"
out = args[1] if len(args) > 1 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
if ref_rows is None:
    fig, (ax0, ax, ax2) = plt.subplots(1, 3, figsize=(15, 4.5))
else:
    fig, (ax0, ax, ax2, ax3) = plt.subplots(1, 4, figsize=(20, 4.5))
names = {3: "F", 6: "FT", 11: "FTS"}
summary = []
def fit_exponent(n, t):
    sel = n >= 400
    if sel.sum() < 3:  # short (CI) runs: fit every point
        sel = n > 0
    return np.polyfit(np.log(n[sel]), np.log(t[sel]), 1)[0]

for dof, name in names.items():
    for threads, style in ((1, "-o"), (2, "--s")):
        steps = sorted((r["params"]["N"], r["phases"]["step"]) for r in rows
                       if r["params"]["dof"] == dof and r["params"]["threads"] == threads and r["phases"].get("step", 0) > 0)
        if steps:
            n, t = np.array(steps).T
            ps = fit_exponent(n, t)
            ax0.loglog(n, t, style, label=f"{name}, {threads} thr (slope {ps:.2f})")
            summary.append((name + " step", threads, ps))
        pts = sorted((r["params"]["N"], r["phases"]["product"]) for r in rows
                     if r["params"]["dof"] == dof and r["params"]["threads"] == threads)
        if not pts:
            continue
        n, t = np.array(pts).T
        p = fit_exponent(n, t)
        ax.loglog(n, t, style, label=f"{name}, {threads} thr (slope {p:.2f})")
        summary.append((name, threads, p))
    one = {r["params"]["N"]: r["phases"]["product"] for r in rows if r["params"]["dof"] == dof and r["params"]["threads"] == 1}
    two = {r["params"]["N"]: r["phases"]["product"] for r in rows if r["params"]["dof"] == dof and r["params"]["threads"] == 2}
    common = sorted(set(one) & set(two))
    if common:
        ax2.semilogx(common, [one[k] / two[k] for k in common], "-o", label=name)
ax0.set_xlabel("N particles")
ax0.set_ylabel("time per step [s]")
ax0.set_title("settling cloud, one time step")
ax0.legend(fontsize=8)
ax.set_xlabel("N particles")
ax.set_ylabel("time per product y = M x [s]")
ax.set_title("direct far field, open domain")
ax.legend(fontsize=8)
ax2.axhline(2.0, color="grey", lw=0.5)
ax2.set_xlabel("N particles")
ax2.set_ylabel("speed-up, 2 threads / 1 thread")
ax2.legend(fontsize=8)
speedups = []
if ref_rows is not None:
    for dof, name in names.items():
        for threads, style in ((1, "-o"), (2, "--s")):
            new = {r["params"]["N"]: r["phases"]["product"] for r in rows
                   if r["params"]["dof"] == dof and r["params"]["threads"] == threads}
            old = {r["params"]["N"]: r["phases"]["product"] for r in ref_rows
                   if r["params"]["dof"] == dof and r["params"]["threads"] == threads}
            common = sorted(set(new) & set(old))
            if common:
                ax3.semilogx(common, [old[k] / new[k] for k in common], style, label=f"{name}, {threads} thr")
                speedups += [(name, threads, k, old[k], new[k]) for k in common]
    ax3.set_xlabel("N particles")
    ax3.set_ylabel("product time: reference loop / vectorised")
    ax3.set_title("vectorised product against its reference twin")
    ax3.legend(fontsize=8)
m = data["machine"]
fig.suptitle(f"{m.get('cpu', '?')}, {m.get('compiler', '?')}, {m.get('git', '?')}, {m.get('date', '?')}", fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=120)
for name, threads, p in summary:
    print(f"{name:3s} {threads} thread(s): fitted exponent {p:.2f}")
if speedups:
    print("| moments | threads | N | reference [s] | vectorised [s] | ratio |")
    print("|---|---|---|---|---|---|")
    for name, threads, n, o, v in speedups:
        print(f"| {name} | {threads} | {int(n)} | {o:.3g} | {v:.3g} | {o / v:.1f} |")
print("wrote", out)
