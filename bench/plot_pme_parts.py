#!/usr/bin/python3
"""Chart the PME error model part by part (bench_pme_parts, issue 12): for each configuration
(moments, phi, tolerance) the achieved error of the real-space truncation, the wave truncation and
the aliasing over their model estimates (est_real, est_wave, est_alias), and the whole product's
achieved / requested error against the band [0.1, 1] that the parameters aim at.

usage: plot_pme_parts.py [RESULTS.json] [OUT.png]   (default: bench/results/pme_parts.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/pme_parts.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = json.load(open(src))["rows"]
labels, parts, whole = [], [], []
for r in rows:
    p, ph = r["params"], r["phases"]
    name = "F" if p["moments"] == 3 else "FTS"
    labels.append(f"{name} φ{p['phi']:.1f}\n{p['tol']:.0e}")
    ratio = lambda meas, est: meas / est if meas >= 0 else np.nan
    parts.append([ratio(ph["real_only"], p["est_real"]), ratio(ph["wave_trunc"], p["est_wave"]),
                  ratio(ph["alias"], p["est_alias"])])
    whole.append(ph["error"] / p["tol"])
parts = np.array(parts)
x = np.arange(len(rows))
fig, (a, b) = plt.subplots(1, 2, figsize=(14, 4.8), gridspec_kw={"width_ratios": [3, 2]})
for k, (lab, col) in enumerate([("real-space truncation", "tab:blue"), ("wave truncation", "tab:green"),
                                ("aliasing", "tab:red")]):
    a.bar(x + (k - 1) * 0.27, parts[:, k], 0.27, label=lab, color=col)
a.axhline(1.0, color="k", lw=0.8)
a.set_yscale("log")
a.set_xticks(x)
a.set_xticklabels(labels, fontsize=7)
a.set_ylabel("achieved error / model estimate")
a.set_title(f"(a) PME error model by part, N = {int(rows[0]['params']['N'])} (– : variant not buildable)")
a.legend(fontsize=8)
b.bar(x, whole, color="tab:gray")
b.axhspan(0.1, 1.0, color="tab:green", alpha=0.15, label="aim: [0.1, 1]")
b.set_yscale("log")
b.set_xticks(x)
b.set_xticklabels(labels, fontsize=7)
b.set_ylabel("achieved / requested error")
b.set_title("(b) the whole product")
b.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("part ratios (real, wave, alias) per row:")
for lab, pr, w in zip(labels, parts, whole):
    print(f"  {lab.replace(chr(10), ' '):22s} {pr[0]:6.2f} {pr[1]:6.2f} {pr[2]:6.2f}   whole {w:.3f}")
print("wrote", out)
