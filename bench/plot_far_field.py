#!/usr/bin/python3
"""Chart the direct far-field benchmark: time per time step and per mobility product against N with
the fitted exponents (log-log least squares over N >= 400, or all points for short runs), and the
2-thread speed-up.

usage: plot_far_field.py [RESULTS.json] [OUT.png]   (defaults: bench/results/far_field_direct.json)
Uses only Debian's python3-numpy and python3-matplotlib.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/far_field_direct.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
fig, (ax0, ax, ax2) = plt.subplots(1, 3, figsize=(15, 4.5))
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
m = data["machine"]
fig.suptitle(f"{m.get('cpu', '?')}, {m.get('compiler', '?')}, {m.get('git', '?')}, {m.get('date', '?')}", fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=120)
for name, threads, p in summary:
    print(f"{name:3s} {threads} thread(s): fitted exponent {p:.2f}")
print("wrote", out)
