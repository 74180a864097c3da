#!/usr/bin/python3
"""Chart the octree far-field benchmark (bench/bench_tree.cpp, issue 16).

  (a, b) time per product against N for F and FTS on 2 threads: one colour per tolerance, the uniform
         cube solid circles, the dense ball dotted squares, exponents fitted over N >= 1e4 in the
         legend; the direct O(N^2) product in black, measured (solid) and scaled by N^2 beyond
         (dashed, labelled "extrapolated");
  (c)    error against theta for each order p (FMM), uniform cloud, F, with C theta^(p+1) guides, and
         Barnes-Hut at p = 0 (the thesis's monopole scheme, black);
  (d)    achieved / requested error against the tolerance (every tolerance-sweep row), the limit 1;
  (e)    2 threads / 1 thread speed-up against N.

Prints markdown tables for docs/benchmarks.md. usage: plot_tree.py [RESULTS.json] [OUT.png]
(defaults bench/results/tree.json, OUT = RESULTS with .png). Debian's python3-numpy/matplotlib only.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/tree.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
NAME = {3: "F", 6: "FT", 11: "FTS"}


def sel(**kw):
    return [r for r in rows if all(r["params"].get(k) == v for k, v in kw.items())]


def fit(ns, ts, lo=1e4):
    ns, ts = np.array(ns), np.array(ts)
    m = ns >= lo
    if m.sum() < 2:
        return None
    return np.polyfit(np.log(ns[m]), np.log(ts[m]), 1)[0]


fig, axes = plt.subplots(2, 3, figsize=(17, 10))
colours = {1e-3: "tab:blue", 1e-4: "tab:green", 1e-6: "tab:red"}
threads = max(r["params"].get("threads", 1) for r in rows)
table = []
for ax, dof in ((axes[0, 0], 3), (axes[0, 1], 11)):
    for tol, col in colours.items():
        for cloud, style in ((0, "o-"), (1, "s:")):
            rs = sorted(sel(kind=0, dof=dof, tol=tol, cloud=cloud, threads=threads), key=lambda r: r["params"]["N"])
            if not rs:
                continue
            ns = [r["params"]["N"] for r in rs]
            ts = [r["phases"]["product"] for r in rs]
            k = fit(ns, ts)
            label = f"tol {tol:.0e} {'cube' if cloud == 0 else 'ball'}" + (f" (N^{k:.2f})" if k else "")
            ax.loglog(ns, ts, style, color=col, label=label, ms=4)
            for r in rs:
                table.append((NAME[dof], "cube" if cloud == 0 else "ball", tol, r))
    ds = sorted(sel(kind=1, dof=dof, threads=threads), key=lambda r: r["params"]["N"])
    if ds:
        ns = np.array([r["params"]["N"] for r in ds])
        ts = np.array([r["phases"]["product"] for r in ds])
        ax.loglog(ns, ts, "k-", lw=2, label="direct (measured)")
        big = np.array([ns[-1], 1e6])
        ax.loglog(big, ts[-1] * (big / ns[-1]) ** 2, "k--", lw=2, label="direct (extrapolated, N^2)")
    ax.set_xlabel("N")
    ax.set_ylabel(f"seconds per product ({threads} threads)")
    ax.set_title(f"({'a' if dof == 3 else 'b'}) {NAME[dof]}: time per product")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)

ax = axes[0, 2]
ps = sorted({r["params"]["p"] for r in sel(kind=2)})
cmap = plt.get_cmap("viridis")
for i, p in enumerate([q for q in ps if q >= 0]):
    rs = sorted(sel(kind=2, set=0, dof=3, p=p), key=lambda r: r["params"]["theta"])
    if not rs:
        continue
    th = np.array([r["params"]["theta"] for r in rs])
    er = np.array([r["phases"]["error"] for r in rs])
    col = cmap(i / max(1, len(ps) - 1))
    ax.loglog(th, er, "o-", color=col, label=f"p = {int(p)}", ms=4)
    ax.loglog(th, er[-1] * (th / th[-1]) ** (p + 1), ":", color=col, lw=1)
    for st, ls in ((1, "--"), (2, "-.")):  # clustered (8 dense balls), radius ratio 10
        rz = sorted(sel(kind=2, set=st, dof=3, p=p), key=lambda r: r["params"]["theta"])
        if rz:
            ax.loglog([r["params"]["theta"] for r in rz], [r["phases"]["error"] for r in rz], ls, color=col, lw=0.8)
rs = sorted(sel(kind=2, set=0, dof=3, p=-1), key=lambda r: r["params"]["theta"])
if rs:
    ax.loglog([r["params"]["theta"] for r in rs], [r["phases"]["error"] for r in rs], "ks-", label="Barnes-Hut p = 0")
ax.set_xlabel("theta")
ax.set_ylabel("relative error against the direct product")
ax.set_title("(c) F: error vs theta; uniform (o), clustered (--), radius ratio 10 (-.)", fontsize=9)
ax.legend(fontsize=7, ncol=2)
ax.grid(True, which="both", alpha=0.3)

ax = axes[1, 0]
for dof, mk in ((3, "o"), (6, "^"), (11, "s")):
    for cloud, col in ((0, "tab:blue"), (1, "tab:orange")):
        rs = sorted(sel(kind=3, dof=dof, cloud=cloud), key=lambda r: r["params"]["tol"])
        if rs:
            ax.loglog([r["params"]["tol"] for r in rs], [r["phases"]["error"] / r["params"]["tol"] for r in rs],
                      mk + "-", color=col, label=f"{NAME[dof]} {'cube' if cloud == 0 else 'ball'}", ms=4)
# the scaling rows (N = 1e3 ... 1e6; direct reference to 2e4, 300 sampled direct rows beyond), 2 threads
sc = [r for r in sel(kind=0, threads=2) if "error" in r["phases"]]
if sc:
    ax.scatter([r["params"]["tol"] * (1.0 + 0.15 * np.log10(r["params"]["N"] / 1e3)) for r in sc],
               [r["phases"]["error"] / r["params"]["tol"] for r in sc], s=10, facecolors="none", edgecolors="gray",
               label="scaling rows, N = 1e3 ... 1e6 (offset right with N)")
ax.axhline(1.0, color="k", lw=1)
ax.set_xlabel("requested tolerance")
ax.set_ylabel("achieved / requested")
ax.set_title("(d) achieved / requested error (must stay below 1)")
ax.legend(fontsize=7)
ax.grid(True, which="both", alpha=0.3)

ax = axes[1, 1]
for dof, mk in ((3, "o"), (11, "s")):
    for tol, col in colours.items():
        pts = []
        for r2 in sel(kind=0, dof=dof, tol=tol, cloud=0, threads=2):
            r1 = sel(kind=0, dof=dof, tol=tol, cloud=0, threads=1, N=r2["params"]["N"])
            if r1:
                pts.append((r2["params"]["N"], r1[0]["phases"]["product"] / r2["phases"]["product"]))
        if pts:
            pts.sort()
            ax.semilogx(*zip(*pts), mk + "-", color=col, label=f"{NAME[dof]} tol {tol:.0e}", ms=4)
ax.axhline(2.0, color="k", lw=1, ls=":")
ax.set_xlabel("N")
ax.set_ylabel("time 1 thread / time 2 threads")
ax.set_title("(e) two-thread speed-up (uniform cube)")
ax.legend(fontsize=7)
ax.grid(True, which="both", alpha=0.3)

ax = axes[1, 2]
for dof, mk in ((3, "o"), (11, "s")):
    for tol, col in colours.items():
        rs = sorted(sel(kind=0, dof=dof, tol=tol, cloud=0, threads=threads), key=lambda r: r["params"]["N"])
        ds = {r["params"]["N"]: r["phases"]["product"] for r in sel(kind=1, dof=dof, threads=threads)}
        if not rs or not ds:
            continue
        nmax = max(ds)
        pts = []
        for r in rs:
            n = r["params"]["N"]
            direct = ds[n] if n in ds else ds[nmax] * (n / nmax) ** 2
            pts.append((n, direct / r["phases"]["product"]))
        ax.loglog(*zip(*pts), mk + "-", color=col, label=f"{NAME[dof]} tol {tol:.0e}", ms=4)
ax.axhline(1.0, color="k", lw=1)
ax.set_xlabel("N")
ax.set_ylabel("direct / tree time (direct extrapolated beyond its last N)")
ax.set_title("(f) speed-up over the direct product (uniform cube)")
ax.legend(fontsize=7)
ax.grid(True, which="both", alpha=0.3)

m = data.get("machine", {})
fig.suptitle(f"Octree far field (FMM) — {m.get('cpu', '')}, git {m.get('git', '')}", fontsize=10)
fig.tight_layout()
fig.savefig(out, dpi=90)
print("wrote", out)

print("\n| moments | cloud | tol | N | theta | p | product [s] | set-up [s] | pairs/N | conversions/N | error | reference |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, cloud, tol, r in table:
    P, ph = r["params"], r["phases"]
    ref = {0: "direct", 1: "tree at tol/1000", 2: "direct, 300 rows", -1: "none"}[int(P["ref"])]
    err = f"{ph['error']:.2e}" if "error" in ph else "–"
    print(f"| {name} | {cloud} | {tol:.0e} | {int(P['N'])} | {P['theta']:.2f} | {int(P['p'])} | {ph['product']:.3g} | "
          f"{ph['setup']:.3g} | {ph['pairs'] / P['N']:.0f} | {ph['conversions'] / P['N']:.1f} | {err} | {ref} |")
print("\n| moments | cloud | tol | theta | p | error | achieved/requested | product [s] |")
print("|---|---|---|---|---|---|---|---|")
for r in sorted(sel(kind=3), key=lambda r: (r["params"]["dof"], r["params"]["cloud"], -r["params"]["tol"])):
    P, ph = r["params"], r["phases"]
    print(f"| {NAME[int(P['dof'])]} | {'cube' if P['cloud'] == 0 else 'ball'} | {P['tol']:.0e} | {P['theta']:.2f} | "
          f"{int(P['p'])} | {ph['error']:.2e} | {ph['error'] / P['tol']:.3f} | {ph['product']:.3g} |")
