#!/usr/bin/python3
"""Chart the fast-PME benchmark (bench/bench_pme.cpp, issue 12); 2-thread times unless stated.

  (a, b) time per product y = M x against N for F and FTS: one colour per tolerance, phi = 0.1 solid
         circles and 0.4 dotted squares, with the exponent fitted over 10^4 <= N <= 10^6 in the legend;
         the previous implementation (bench/results/ewald_pme.json and pme_large.json, commit 07f964e,
         radii 0.5-1.5, phi 0.1) dashed at the same tolerances, and the direct O(N^2) product in black
         (measured, dotted where scaled by N^2);
  (c)    phases (set-up, wave, real, product) against N, FTS, tol 1e-4;
  (d)    speed-accuracy: time per product against the achieved error at N = 10^4 and 10^5, phi = 0.1,
         F and FTS, tolerances 1e-2 ... 1e-10 (labelled), direct product levels;
  (e)    achieved / requested error against the tolerance, every PME row, goal band [0.1, 1];
  (f)    speed-ups: previous / new implementation on the previous benchmark's own configurations
         (kind 3 rows against the old files, same N, tolerance, moments and threads), and 2 threads / 1.

Prints the goal table of issue 12. usage: plot_pme.py [RESULTS.json] [OUT.png]
(defaults bench/results/pme.json, OUT = RESULTS with .png); the previous results are read from the
results folder next to this script. Uses only Debian's python3-numpy and python3-matplotlib.
"""
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/pme.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
data = json.load(open(src))
rows = data["rows"]
old = []
for name in ("ewald_pme.json", "pme_large.json"):
    path = os.path.join(here, name)
    if os.path.exists(path):
        old += [r for r in json.load(open(path))["rows"] if r["params"].get("kind", 0) == 0]
NAME = {3: "F", 11: "FTS"}
FIT_LO, FIT_HI = 1e4, 1e6


def P(r, k, d=None):
    return r["params"].get(k, d)


def sel(rs, **kw):
    return [r for r in rs if all(P(r, k) == v for k, v in kw.items())]


def series(rs, phase="product", x="N"):
    pts = sorted((P(r, x), r["phases"][phase]) for r in rs if phase in r["phases"])
    return np.array(pts).T if pts else (np.array([]), np.array([]))


def exponent(n, t, lo=FIT_LO, hi=FIT_HI):
    fit = (n >= lo * 0.999) & (n <= hi * 1.001)
    if fit.sum() < 2:
        return float("nan")
    return np.polyfit(np.log(n[fit]), np.log(t[fit]), 1)[0]


def one(rs, phase="product"):
    return rs[0]["phases"][phase] if rs else float("nan")


pme = sel(rows, kind=0)
acc = [r for r in pme if P(r, "error", -1.0) > 0]  # rows with a reference (error -1: none fitted in memory)
threads = max(P(r, "threads") for r in pme)
tols = sorted({P(r, "tol") for r in pme}, reverse=True)
base_tols = [t for t in (1e-3, 1e-4, 1e-6) if t in tols]
cmap = plt.get_cmap("viridis")
colour = {t: cmap(i / max(1, len(tols) - 1) * 0.9) for i, t in enumerate(tols)}
direct = sel(rows, kind=1)

fig, axes = plt.subplots(2, 3, figsize=(19, 11))
fig.suptitle(f"Fast PME (issue 12), {data['machine'].get('cpu', '')}, git {data['machine'].get('git', '?')}, "
             f"{threads} threads unless stated")
summary = []

# (a, b) time against N.
for ax, dof in ((axes[0, 0], 3), (axes[0, 1], 11)):
    for tol in base_tols:
        for phi, style in ((0.1, "o-"), (0.4, "s:")):
            n, t = series(sel(pme, dof=dof, tol=tol, phi=phi, threads=threads))
            if len(n) == 0:
                continue
            e = exponent(n, t)
            summary.append((NAME[dof], phi, tol, e, exponent(*series(sel(pme, dof=dof, tol=tol, phi=phi, threads=1)))))
            ax.loglog(n, t, style, color=colour[tol], ms=4, label=f"tol {tol:.0e}, $\\phi$={phi}: $N^{{{e:.2f}}}$")
        n, t = series(sel(old, dof=dof, tol=tol, threads=threads))
        if len(n):
            ax.loglog(n, t, "x--", color=colour[tol], alpha=0.7, label=f"previous, tol {tol:.0e}")
    n, t = series(sel(direct, dof=dof))
    if len(n):
        ax.loglog(n, t, "k^-", label="direct $O(N^2)$ (open)")
        nn = np.array([n[-1], 1e5])
        ax.loglog(nn, t[-1] * (nn / n[-1]) ** 2, "k:", label="direct, $N^2$-scaled")
    ax.axhline(0.1, color="red", lw=0.6, ls="-.")
    ax.set_xlabel("N")
    ax.set_ylabel("time per product [s]")
    ax.set_title(f"({'a' if dof == 3 else 'b'}) {NAME[dof]}: time per product (fit {FIT_LO:.0e}..{FIT_HI:.0e})")
    ax.legend(fontsize=6.5, ncol=2)
    ax.grid(True, which="both", alpha=0.3)

# (c) phases.
ax = axes[0, 2]
for phase, c in (("setup", "tab:grey"), ("wave", "tab:blue"), ("real", "tab:orange"), ("product", "k")):
    for phi, style in ((0.1, "o-"), (0.4, "s:")):
        n, t = series(sel(pme, dof=11, tol=1e-4, phi=phi, threads=threads), phase)
        if len(n):
            ax.loglog(n, t, style, color=c, ms=4, label=f"{phase}, $\\phi$={phi}")
ax.set_xlabel("N")
ax.set_ylabel("time [s]")
ax.set_title("(c) FTS, tol 1e-4: phases")
ax.legend(fontsize=7)
ax.grid(True, which="both", alpha=0.3)

# (d) speed-accuracy.
ax = axes[1, 0]
acc_n = sorted({P(r, "N") for r in pme if P(r, "tol") in (1e-2, 1e-10)})
markers = {3: "o", 11: "s"}
for i, n0 in enumerate(acc_n):
    for dof in (3, 11):
        rs = sorted(sel(acc, dof=dof, N=n0, phi=0.1, threads=threads), key=lambda r: -P(r, "tol"))
        if not rs:
            continue
        e = [P(r, "error") for r in rs]
        t = [r["phases"]["product"] for r in rs]
        line, = ax.loglog(e, t, markers[dof] + ("-" if i == 0 else "--"), ms=5,
                          label=f"PME {NAME[dof]}, N={n0:.0e}")
        for r, x, y in zip(rs, e, t):
            ax.annotate(f"{P(r, 'tol'):.0e}", (x, y), fontsize=5.5, xytext=(2, 2), textcoords="offset points")
        d = sel(direct, dof=dof, N=n0)
        if d:
            ax.axhline(one(d), color=line.get_color(), lw=0.8, ls="-.", label=f"direct {NAME[dof]}, N={n0:.0e}")
        else:
            dd = sorted(sel(direct, dof=dof), key=lambda r: P(r, "N"))
            if dd:
                lvl = one(dd[-1:]) * (n0 / P(dd[-1], "N")) ** 2
                ax.axhline(lvl, color=line.get_color(), lw=0.8, ls=":",
                           label=f"direct {NAME[dof]}, N={n0:.0e} ($N^2$ from {P(dd[-1], 'N'):.0e})")
ax.set_xlabel("achieved relative error")
ax.set_ylabel("time per product [s]")
ax.set_title("(d) speed-accuracy, $\\phi$ = 0.1 (labels: requested tol)")
ax.legend(fontsize=6.5)
ax.grid(True, which="both", alpha=0.3)

# (e) achieved / requested.
ax = axes[1, 1]
ax.axhspan(0.1, 1.0, color="green", alpha=0.1, label="goal [0.1, 1]")
for dof, mk in markers.items():
    for phi, fill in ((0.1, "full"), (0.4, "none")):
        rs = sel(acc, dof=dof, phi=phi, threads=threads)
        if rs:
            ax.loglog([P(r, "tol") for r in rs], [P(r, "error") / P(r, "tol") for r in rs], mk, fillstyle=fill,
                      ms=5, alpha=0.7, label=f"{NAME[dof]}, $\\phi$={phi}")
ax.set_xlabel("requested tolerance")
ax.set_ylabel("achieved / requested")
ax.set_title("(e) achieved / requested error (all N)")
ax.legend(fontsize=7)
ax.grid(True, which="both", alpha=0.3)

# (f) speed-ups.
ax = axes[1, 2]
prev = sel(rows, kind=3)
ratios = []
for dof in (3, 11):
    for tol in (1e-3, 1e-4, 1e-6):
        for thr, style in ((threads, "o-"), (1, "x:")):
            pts = []
            for r in sel(prev, dof=dof, tol=tol, threads=thr):
                o = sel(old, dof=dof, tol=tol, threads=thr, N=P(r, "N"))
                if o:
                    pts.append((P(r, "N"), one(o) / r["phases"]["product"]))
                    ratios.append((NAME[dof], tol, thr, P(r, "N"), pts[-1][1]))
            if pts and tol == 1e-4:
                n, s = np.array(sorted(pts)).T
                ax.loglog(n, s, style, label=f"previous / new, {NAME[dof]} tol {tol:.0e}, {thr} thr")
for dof, c in ((3, "tab:green"), (11, "tab:red")):
    for phi, style in ((0.1, "o-"), (0.4, "s:")):
        a = {P(r, "N"): r["phases"]["product"] for r in sel(pme, dof=dof, tol=1e-4, phi=phi, threads=1)}
        b = {P(r, "N"): r["phases"]["product"] for r in sel(pme, dof=dof, tol=1e-4, phi=phi, threads=threads)}
        n = sorted(set(a) & set(b))
        if n and threads > 1:
            ax.semilogx(n, [a[k] / b[k] for k in n], style, color=c, ms=4,
                        label=f"{threads} thr / 1 thr, {NAME[dof]} tol 1e-4 $\\phi$={phi}")
ax.axhline(1.8, color=("tab:red"), lw=0.6, ls="-.")
le = sel(rows, kind=2)
le_text = []
for n0 in sorted({P(r, "N") for r in le}):
    for thr in sorted({P(r, "threads") for r in le}, reverse=True):
        base = sel(le, N=n0, threads=thr, strain=0.0)
        if base:
            r3, r31 = sel(le, N=n0, threads=thr, strain=0.3), sel(le, N=n0, threads=thr, strain=0.31)
            le_text.append(f"LE N={n0:.0e} {thr} thr: sheared/unsheared {one(r3) / one(base):.2f}, "
                           f"after strain change {one(r31) / one(base):.2f}")
ax.text(0.02, 0.45, "\n".join(le_text), transform=ax.transAxes, fontsize=7, va="top")
ax.set_xlabel("N")
ax.set_ylabel("speed-up")
ax.set_title("(f) previous/new (same configurations); threads")
ax.legend(fontsize=6.5)
ax.grid(True, which="both", alpha=0.3)

fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")

# --- goal table ----------------------------------------------------------------------------------
print("\nGoals of issue 12 (times on", threads, "threads):")
g = sel(pme, dof=11, N=1e4, phi=0.4, tol=1e-4, threads=threads)
print(f"  FTS, N = 1e4, phi 0.4, tol 1e-4: {one(g):.4f} s per product (goal <= 0.1 s)" if g
      else "  FTS, N = 1e4, phi 0.4, tol 1e-4: not measured")
print("  exponent of time per product over 1e4..1e6 (goal <= 1.1):")
for m, phi, tol, e2, e1 in summary:
    print(f"    {m:3s} phi {phi} tol {tol:.0e}: {e2:.3f} ({threads} thr), {e1:.3f} (1 thr)")
print("  cost(1e-6) / cost(1e-3) (goal <= 2):")
cr = []
for dof in (3, 11):
    for phi in (0.1, 0.4):
        for n0 in sorted({P(r, "N") for r in pme}):
            a = sel(pme, dof=dof, phi=phi, N=n0, tol=1e-6, threads=threads)
            b = sel(pme, dof=dof, phi=phi, N=n0, tol=1e-3, threads=threads)
            if a and b:
                cr.append((NAME[dof], phi, n0, one(a) / one(b)))
for m in ("F", "FTS"):
    for phi in (0.1, 0.4):
        v = [(n0, c) for mm, p, n0, c in cr if mm == m and p == phi]
        if v:
            print(f"    {m:3s} phi {phi}: " + ", ".join(f"N={n0:.0e} {c:.2f}" for n0, c in v))
print("  achieved / requested (goal within [0.1, 1]):")
for tol in tols:
    v = [P(r, "error") / tol for r in sel(acc, tol=tol)]
    if not v:
        continue
    print(f"    tol {tol:.0e}: {min(v):.3f} .. {max(v):.3f} over {len(v)} rows")
v = [P(r, "error") / P(r, "tol") for r in acc]
print(f"    all rows: {min(v):.3f} .. {max(v):.3f}; outside [0.1, 1]: {sum(1 for x in v if not 0.1 <= x <= 1)}"
      f" of {len(v)}; rows without a reference: {len(pme) - len(acc)}")
for r in acc:
    if not 0.1 <= P(r, "error") / P(r, "tol") <= 1:
        print(f"      outside: {NAME[P(r, 'dof')]} N={P(r, 'N'):.0f} phi {P(r, 'phi')} tol {P(r, 'tol'):.0e} "
              f"{P(r, 'threads'):.0f} thr: {P(r, 'error') / P(r, 'tol'):.3f}")
print(f"  {threads} threads / 1 thread, product (goal >= 1.8):")
for dof in (3, 11):
    for phi in (0.1, 0.4):
        s = []
        for r in sel(pme, dof=dof, phi=phi, threads=1):
            b = sel(pme, dof=dof, phi=phi, N=P(r, "N"), tol=P(r, "tol"), threads=threads)
            if b:
                s.append((P(r, "N"), P(r, "tol"), r["phases"]["product"] / one(b)))
        big = [x for n0, t, x in s if n0 >= 1e4]
        if s:
            print(f"    {NAME[dof]:3s} phi {phi}: all N {min(x for _, _, x in s):.2f} .. {max(x for _, _, x in s):.2f}"
                  + (f"; N >= 1e4 {min(big):.2f} .. {max(big):.2f} (median {np.median(big):.2f})" if big else ""))
print("  Lees-Edwards, FTS tol 1e-4 (goal: sheared within 10 % of unsheared):")
for n0 in sorted({P(r, "N") for r in le}):
    for thr in sorted({P(r, "threads") for r in le}, reverse=True):
        b, r3, r31 = (sel(le, N=n0, threads=thr, strain=s) for s in (0.0, 0.3, 0.31))
        if b and r3 and r31:
            print(f"    N={n0:.0e} {thr} thr: product {one(b):.4f} / {one(r3):.4f} / {one(r31):.4f} s "
                  f"(strain 0 / 0.3 / 0.31): ratio {one(r3) / one(b):.3f}, {one(r31) / one(b):.3f}; "
                  f"set-up {one(b, 'setup'):.3f} / {one(r3, 'setup'):.3f} s, set_configuration(0.31) "
                  f"{one(r31, 'setup'):.3f} s, grid kept {bool(P(r31[0], 'kept'))}, "
                  f"grid {P(b[0], 'grid0'):.0f} / {P(r3[0], 'grid0'):.0f}x{P(r3[0], 'grid1'):.0f}x"
                  f"{P(r3[0], 'grid2'):.0f}, errors {P(b[0], 'error'):.1e} / {P(r3[0], 'error'):.1e} / "
                  f"{P(r31[0], 'error'):.1e}, vs new object {P(r31[0], 'fresh_diff'):.1e}")
print("  previous / new on the previous configurations (same N, tol, moments, threads):")
for m in ("F", "FTS"):
    for thr in (threads, 1):
        v = [(n0, tol, s) for mm, tol, t, n0, s in ratios if mm == m and t == thr]
        if v:
            print(f"    {m:3s} {thr} thr: " + ", ".join(f"N={n0:.0f} {tol:.0e}: {s:.1f}" for n0, tol, s in v))
print("  memory: peak RSS [MB] at tol 1e-4 / reference:")
seen = set()
for r in sel(rows, kind=4):
    if P(r, "strain", 0.0) == 0.0 and P(r, "N") >= 1e5 and (P(r, "N"), P(r, "phi"), P(r, "dof")) not in seen:
        seen.add((P(r, "N"), P(r, "phi"), P(r, "dof")))
        t4 = sel(pme, N=P(r, "N"), phi=P(r, "phi"), dof=P(r, "dof"), tol=1e-4, threads=threads)
        print(f"    {NAME[P(r, 'dof')]:3s} N={P(r, 'N'):.0e} phi {P(r, 'phi')}: {P(t4[0], 'rss_mb') if t4 else float('nan'):.0f}"
              f" / {P(r, 'rss_mb'):.0f} (reference tol {P(r, 'ref_tol'):.0e}: setup {one([r], 'setup'):.1f} s,"
              f" product {one([r]):.1f} s)")

# --- markdown tables for docs/benchmarks.md --------------------------------------------------------
print("\nTime per product [s], %d threads (1 thread in brackets where measured):\n" % threads)
cols = [(dof, phi, tol) for dof in (3, 11) for phi in (0.1, 0.4) for tol in base_tols]
print("| N | " + " | ".join(f"{NAME[d]} {p} {t:.0e}" for d, p, t in cols) + " |")
print("|---" * (len(cols) + 1) + "|")
for n0 in sorted({P(r, "N") for r in pme}):
    cells = []
    for d, p, t in cols:
        a, b = sel(pme, dof=d, phi=p, tol=t, N=n0, threads=threads), sel(pme, dof=d, phi=p, tol=t, N=n0, threads=1)
        cells.append((f"{one(a):.3g}" if a else "–") + (f" ({one(b):.3g})" if b else ""))
    print(f"| {n0:.0f} | " + " | ".join(cells) + " |")
print("\nTolerance 1e-4, %d threads: parameters, phases [s], error, memory:\n" % threads)
print("| moments | phi | N | grid | P | pairs/N | set-up | wave | real | product | model | error/tol | peak RSS MB |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for d in (3, 11):
    for p in (0.1, 0.4):
        for r in sorted(sel(pme, dof=d, phi=p, tol=1e-4, threads=threads), key=lambda r: P(r, "N")):
            ph = r["phases"]
            e = P(r, "error")
            print(f"| {NAME[d]} | {p} | {P(r, 'N'):.0f} | {P(r, 'grid'):.0f} | {P(r, 'support'):.0f} | "
                  f"{P(r, 'pairs_per_particle'):.0f} | {ph['setup']:.3g} | {ph['wave']:.3g} | {ph['real']:.3g} | "
                  f"{ph['product']:.3g} | {P(r, 'est_cost'):.3g} | " + (f"{e / 1e-4:.2f}" if e > 0 else "–")
                  + f" | {P(r, 'rss_mb'):.0f} |")
