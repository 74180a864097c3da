#!/usr/bin/python3
"""Chart the cloud settling validation (bench/validate_cloud.cpp, issue 18).

  (a) monodisperse clouds: measured mean velocity / the thesis's eq. 4.6 against phi, one colour per
      N (mean over seeds, bars = spread min..max, filled circles); open squares, dashed: measured /
      Nitsche & Batchelor's form (4.6 + U_St) with the radius R_eff of the sphere the centres fill;
  (b) the same for lognormal LN(-0.35, 0.04) radii;
  (c) bidisperse clouds (N = 1000, phi = 0.05, lambda = 0.5): measured and eq. 4.6 against the
      number fraction nu of small spheres (units of the large spheres' U0).

Prints markdown tables for docs/clouds.md. usage: plot_cloud.py [RESULTS.json] [OUT.png]
(defaults bench/results/cloud.json, OUT = RESULTS with .png). Debian's python3-numpy/matplotlib only.
"""
import json
import sys
from collections import defaultdict

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/cloud.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = json.load(open(src))["rows"]


def groups(kind, key):
    g = defaultdict(list)
    for r in rows:
        p = r["params"]
        if p["kind"] == kind:
            g[tuple(p[k] for k in key)].append(r["phases"])
    return g


fig, axs = plt.subplots(1, 3, figsize=(16, 4.8))
names = {0: "monodisperse", 1: "lognormal LN(-0.35, 0.04)"}
for kind, ax in ((0, axs[0]), (1, axs[1])):
    g = groups(kind, ("N", "phi"))
    Ns = sorted({k[0] for k in g})
    print(f"\n{names[kind]}: U_sim / U_(4.6) (mean over seeds; min..max); U_(4.6) and NB ratio (4.6 + <U_St>)/(4.6)\n")
    print("| N | phi | U_(4.6) / U0 | U_sim / U0 | U_sim / U_(4.6) | spread | (4.6 + U_St) / 4.6 | U_sim / U_NB(R_eff) |")
    print("|---|---|---|---|---|---|---|---|")
    for i, N in enumerate(Ns):
        phis = sorted(k[1] for k in g if k[0] == N)
        ratio = [np.array([v["U_sim"] / v["U_formula"] for v in g[(N, p)]]) for p in phis]
        nb = [np.mean([v["U_nb"] / v["U_formula"] for v in g[(N, p)]]) for p in phis]
        eff = [np.mean([v["U_sim"] / v["U_nb_eff"] for v in g[(N, p)]]) for p in phis]
        m = np.array([r.mean() for r in ratio])
        lo = m - np.array([r.min() for r in ratio])
        hi = np.array([r.max() for r in ratio]) - m
        c = f"C{i}"
        ax.errorbar(phis, m, yerr=[lo, hi], fmt="o-", color=c, capsize=3, label=f"N = {int(N)}")
        ax.plot(phis, eff, "s--", color=c, mfc="none", alpha=0.8)
        for p, r, q, e in zip(phis, ratio, nb, eff):
            vs = g[(N, p)]
            print(f"| {int(N)} | {p:g} | {np.mean([v['U_formula'] for v in vs]):.2f} | {np.mean([v['U_sim'] for v in vs]):.2f} "
                  f"| {r.mean():.4f} | {r.min():.4f}..{r.max():.4f} | {q:.4f} | {e:.4f} |")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel(r"volume fraction $\phi$")
    ax.set_ylabel(r"measured $U_c$ / prediction")
    ax.set_title(f"({'ab'[kind]}) {names[kind]}: measured / eq. 4.6 (filled)\n"
                 f"measured / (4.6 + $U_{{St}}$) with the centres' radius (open, dashed)", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)

g = groups(2, ("nu",))
nus = sorted(k[0] for k in g)
sim = [np.mean([v["U_sim"] for v in g[(n,)]]) for n in nus]
smin = [min(v["U_sim"] for v in g[(n,)]) for n in nus]
smax = [max(v["U_sim"] for v in g[(n,)]) for n in nus]
form = [np.mean([v["U_formula"] for v in g[(n,)]]) for n in nus]
ax = axs[2]
ax.errorbar(nus, sim, yerr=[np.array(sim) - smin, np.array(smax) - sim], fmt="o", capsize=3, label="measured (mean, min..max)")
ax.plot(nus, form, "k-", label="eq. 4.6 (sampled radii)")
ax.set_xlabel(r"number fraction of small spheres $\nu$")
ax.set_ylabel(r"$U_c / U_0$ (large spheres' Stokes velocity)")
ax.set_title(r"(c) bidisperse, N = 1000, $\phi$ = 0.05, $\lambda$ = 0.5", fontsize=10)
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
print("\nbidisperse N = 1000, phi = 0.05, lambda = 0.5\n")
eff = [np.mean([v["U_sim"] / v["U_nb_eff"] for v in g[(n,)]]) for n in nus]
print("| nu | U_(4.6) / U0 | U_sim / U0 | U_sim / U_(4.6) | U_sim / U_NB(R_eff) |")
print("|---|---|---|---|---|")
for n, s, f, e in zip(nus, sim, form, eff):
    print(f"| {n:g} | {f:.2f} | {s:.2f} | {s / f:.4f} | {e:.4f} |")
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"\nwrote {out}")
