#!/usr/bin/python3
"""Chart the periodic far-field benchmark (bench/bench_ewald.cpp), 1-thread times unless stated:

  (a, b) time per product y = M x against N, for F and FTS: PME (one line per tolerance), the dense
         Ewald matrix (matvec, and its build dotted) and the open-domain direct O(N^2) product, each
         with its log-log exponent in the legend (least squares over N >= 400 when a line has >= 3
         such points, else over all its points);
  (c)    the speed-accuracy chart: PME time per product against the achieved error
         ||M_pme x - M_ref x|| / ||M_ref x|| at the largest N present for every tolerance in F and FTS,
         labelled by the requested tolerance (hollow grey markers at the requested value, dotted to the
         achieved one), with the direct product at that N as a level;
  (d)    speed-up of 2 threads over 1 for PME (loosest and tightest tolerance) and direct.

Prints the fitted exponents, the achieved errors against the tolerances and the speed-up ratios.

usage: plot_ewald.py [RESULTS.json] [OUT.png]   (defaults: bench/results/ewald_pme.json, OUT = .png)
Rows without "kind" (older files) are PME rows. Uses only Debian's python3-numpy and python3-matplotlib.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/ewald_pme.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
PME, EWALD, DIRECT = 0, 1, 2
MOMENTS = {3: "F", 11: "FTS"}


def sel(kind, dof, threads=1, tol=None):
    """Rows of one kind, moment and thread count (and tolerance for PME)."""
    return [r for r in rows
            if r["params"].get("kind", PME) == kind and r["params"]["dof"] == dof
            and r["params"]["threads"] == threads and (tol is None or r["params"]["tol"] == tol)]


def series(rs, phase="product"):
    pts = sorted((r["params"]["N"], r["phases"][phase]) for r in rs if phase in r["phases"])
    return (np.array(pts).T if pts else (np.array([]), np.array([])))


def exponent(n, t):
    if len(n) < 2:
        return float("nan")
    fit = n >= 400
    if fit.sum() < 3:
        fit = n > 0
    return np.polyfit(np.log(n[fit]), np.log(t[fit]), 1)[0]


tols = sorted({r["params"]["tol"] for r in rows if r["params"].get("kind", PME) == PME}, reverse=True)
cmap = plt.get_cmap("viridis")
colour = {tol: cmap(i / max(1, len(tols) - 1) * 0.9) for i, tol in enumerate(tols)}
fig, axes = plt.subplots(2, 2, figsize=(13, 10))
exponents = []

# (a, b) time against N.
for ax, (dof, name) in zip(axes[0], MOMENTS.items()):
    for tol in tols:
        n, t = series(sel(PME, dof, tol=tol))
        if len(n):
            p = exponent(n, t)
            exponents.append((name, f"PME tol {tol:.0e}", p))
            ax.loglog(n, t, "-o", ms=4, color=colour[tol], label=f"PME tol {tol:.0e} (slope {p:.2f})")
    n, t = series(sel(DIRECT, dof))
    if not len(n):  # older files: the direct time is a phase of the PME rows
        n, t = series(sel(PME, dof, tol=tols[0]) if tols else [], "direct")
    if len(n):
        p = exponent(n, t)
        exponents.append((name, "direct (open domain)", p))
        ax.loglog(n, t, "-s", color="black", label=f"direct, open domain (slope {p:.2f})")
    for phase, style, label in (("product", "-^", "Ewald dense, matvec"), ("build", ":^", "Ewald dense, build")):
        n, t = series(sel(EWALD, dof), phase)
        if len(n):
            p = exponent(n, t)
            exponents.append((name, label, p))
            ax.loglog(n, t, style, color="tab:red", label=f"{label} (slope {p:.2f})")
    ax.set_xlabel("N particles")
    ax.set_ylabel("time [s] (1 thread)")
    ax.set_title(f"{name}: time per product against N")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", lw=0.3)

# (c) speed against accuracy at the largest N that has every tolerance in both moments.
ax = axes[1][0]
have = None
for dof in MOMENTS:
    for tol in tols:
        ns = {r["params"]["N"] for r in sel(PME, dof, tol=tol) if "error" in r["params"]}
        have = ns if have is None else have & ns
n_common = max(have) if have else None
if n_common is not None:
    for dof, name, marker in ((3, "F", "o"), (11, "FTS", "s")):
        pts = sorted((r["params"]["error"], r["phases"]["product"], r["params"]["tol"], r["params"].get("reference", -1))
                     for r in sel(PME, dof) if r["params"]["N"] == n_common)
        e, t, tl, ref = np.array(pts).T
        ax.loglog(e, t, "-" + marker, color="tab:blue" if dof == 3 else "tab:orange", label=f"PME, {name}")
        for ei, ti, tli in zip(e, t, tl):
            ax.annotate(f"{tli:.0e}", (ei, ti), textcoords="offset points", xytext=(4, 4), fontsize=7)
            ax.plot([tli, ei], [ti, ti], ":", color="grey", lw=0.6)
        ax.loglog(tl, t, marker, mfc="none", color="grey", label=f"requested tol, {name}")
        d = [r["phases"]["product"] for r in sel(DIRECT, dof) if r["params"]["N"] == n_common]
        if d:
            ax.axhline(d[0], ls="--", lw=0.8, color="tab:blue" if dof == 3 else "tab:orange",
                       label=f"direct, open domain, {name}")
    refname = {0: "dense Ewald", 1: "PME at tol 1e-12"}.get(int(ref[0]), "?")
    ax.set_title(f"speed-accuracy at N = {n_common:.0f} (labels: requested tol; reference: {refname})", fontsize=9)
    ax.invert_xaxis()
    ax.margins(x=0.08, y=0.08)
    ax.legend(fontsize=7)
else:
    ax.set_title("speed-accuracy: no rows with an achieved error")
ax.set_xlabel("achieved relative error ||M x - M_ref x|| / ||M_ref x||")
ax.set_ylabel("time per product [s] (1 thread)")
ax.grid(True, which="both", lw=0.3)

# (d) 2 threads over 1.
ax = axes[1][1]
speedups = []
for dof, name in MOMENTS.items():
    lines = [(f"PME tol {tol:.0e}", PME, tol) for tol in tols] + [("direct", DIRECT, None)]
    for label, kind, tol in lines:
        one = dict(zip(*series(sel(kind, dof, 1, tol))))
        two = dict(zip(*series(sel(kind, dof, 2, tol))))
        common = sorted(set(one) & set(two))
        if not common:
            continue
        ratio = [one[k] / two[k] for k in common]
        speedups.append((name, label, common, ratio))
        if kind == DIRECT or tol in (tols[0], tols[-1]):
            style = ("-" if dof == 3 else "--") + ("s" if kind == DIRECT else "o")
            ax.semilogx(common, ratio, style, color="black" if kind == DIRECT else colour[tol], label=f"{name}, {label}")
ax.axhline(2.0, color="grey", lw=0.5)
ax.axhline(1.0, color="grey", lw=0.5)
ax.set_xlabel("N particles")
ax.set_ylabel("speed-up, 2 threads / 1 thread (product)")
ax.set_title("thread scaling (solid F, dashed FTS)")
ax.legend(fontsize=7)
ax.grid(True, which="both", lw=0.3)

m = data["machine"]
fig.suptitle(f"periodic far field: PME vs dense Ewald vs direct -- {m.get('cpu', '?')}, {m.get('compiler', '?')}, "
             f"{m.get('git', '?')}, {m.get('date', '?')}", fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=110)

print("fitted log-log exponents (time per product against N, 1 thread):")
for name, label, p in exponents:
    print(f"  {name:3s} {label:28s} {p:.2f}")
print("achieved error against requested tolerance (reference 0 = dense Ewald, 1 = PME at 1e-12):")
for dof, name in MOMENTS.items():
    for r in sorted(sel(PME, dof), key=lambda r: (r["params"]["N"], -r["params"]["tol"])):
        q = r["params"]
        if "error" in q:
            print(f"  {name:3s} N={q['N']:6.0f} tol={q['tol']:.0e} error={q['error']:.2e} "
                  f"(error/tol {q['error'] / q['tol']:.1e}, reference {q.get('reference', -1):.0f}) "
                  f"product {r['phases']['product']:.4f} s")
for dof, name in MOMENTS.items():
    for r in sel(EWALD, dof):
        q = r["params"]
        print(f"  {name:3s} N={q['N']:6.0f} PME tol 1e-12 against dense Ewald: {q.get('pme12_error', float('nan')):.2e}")
print("time ratios at each N, 1 thread (>1: PME faster):")
for dof, name in MOMENTS.items():
    direct = dict(zip(*series(sel(DIRECT, dof))))
    ewald = dict(zip(*series(sel(EWALD, dof))))
    for tol in tols:
        pme = dict(zip(*series(sel(PME, dof, tol=tol))))
        s = "  ".join(f"N={k:.0f}: direct/PME {direct[k] / pme[k]:.2f}" +
                      (f", Ewald matvec/PME {ewald[k] / pme[k]:.3f}" if k in ewald else "")
                      for k in sorted(pme) if k in direct)
        print(f"  {name:3s} tol {tol:.0e}: {s}")
print("speed-up, 2 threads / 1 thread:")
for name, label, common, ratio in speedups:
    print(f"  {name:3s} {label:16s} " + "  ".join(f"N={k:.0f}: {x:.2f}" for k, x in zip(common, ratio)))
print("wrote", out)
