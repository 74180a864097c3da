#!/usr/bin/python3
"""Chart the 1D PME window study (bench/bench_windows.cpp; docs/pme_windows.md):

  (a-e) smallest support P meeting the tolerance (max error <= tol) against tol, one panel per grid
        upsampling sigma, one colour per window (Gaussian, ES, KB); solid: the value window, dotted:
        value and derivative window on both sides (at the value-optimal shape);
  (f, g) max error against P with the optimal shape at each P, sigma = 1.25 and 2, for the spectra
        of tol = 1e-4 (dashed) and 1e-10 (solid);
  (h)   derivative (one side) error against the distance of a grid point from the support edge at
        the support meeting tol with derivative windows (P_d2),
        sigma = 2 (the ES derivative is unbounded at the edge).

Prints markdown tables (P and beta/P per window, tol, sigma; derivative P; per window the cheapest
sigma and P of the 3D cost model and its cost relative to the cheapest window;
measured c_s, c_f, window evaluation times) and least-squares rules P = a + b log10(1/tol) and
beta/P = c + d / sigma, for docs/pme_windows.md.

usage: plot_windows.py [RESULTS.json] [OUT.png]   (defaults: bench/results/windows.json, OUT = .png)
Uses only Debian's python3-numpy and python3-matplotlib.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/windows.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = [r["params"] | {"_ph": r["phases"]} for r in json.load(open(src))["rows"]]
NAMES = ["Gaussian", "ES", "KB"]
COLOURS = ["tab:blue", "tab:red", "tab:green"]


def kind(k):
    return [r for r in rows if r["kind"] == k]


minimal = kind(1)
curves = kind(0)
sigmas = sorted({r["sigma"] for r in minimal})
tols = sorted({r["tol"] for r in minimal}, reverse=True)

fig, axes = plt.subplots(2, 4, figsize=(19, 9))
axes = axes.ravel()
for a, sigma in zip(axes, sigmas):
    for w in range(3):
        sel = sorted((r for r in minimal if r["window"] == w and r["sigma"] == sigma), key=lambda r: -r["tol"])
        t = [r["tol"] for r in sel if r["P"] > 0]
        a.plot(t, [r["P"] for r in sel if r["P"] > 0], "o-", color=COLOURS[w], label=NAMES[w])
        both = [(r["tol"], max(r["P"], r["P_d2"])) for r in sel if r["P"] > 0 and r["P_d2"] > 0]
        if both:
            a.plot(*zip(*both), "s:", color=COLOURS[w], ms=4, label=NAMES[w] + ", with derivative")
    a.set_xscale("log")
    a.invert_xaxis()
    a.set_xlabel("tolerance (max error)")
    a.set_ylabel("support P (grid points)")
    a.set_title(f"smallest P, sigma = {sigma:g}")
    a.grid(alpha=0.3)
    a.legend(fontsize=7)
panel = len(sigmas)
for sigma in (1.25, 2.0):
    if panel >= 7 or sigma not in sigmas:
        continue
    a = axes[panel]
    panel += 1
    for tol, style in ((1e-4, "--"), (1e-10, "-")):
        for w in range(3):
            sel = sorted((r for r in curves if r["window"] == w and r["sigma"] == sigma and r["tol"] == tol),
                         key=lambda r: r["P"])
            if sel:
                a.semilogy([r["P"] for r in sel], [max(r["err_max"], 1e-17) for r in sel], style,
                           color=COLOURS[w], label=f"{NAMES[w]}, spectrum tol {tol:g}")
    a.set_xlabel("support P")
    a.set_ylabel("max error / sum |g|")
    a.set_title(f"error vs P, optimal shape, sigma = {sigma:g}")
    a.grid(alpha=0.3)
    a.legend(fontsize=7)
edge = [r for r in kind(7) if r["sigma"] == 2.0]
if edge:
    a = axes[7]
    etol = min(r["tol"] for r in edge)
    for w in range(3):
        sel = sorted((r for r in edge if r["window"] == w and r["tol"] == etol), key=lambda r: r["eps"])
        if sel:
            a.loglog([r["eps"] for r in sel], [r["d1_max"] for r in sel], "o-", color=COLOURS[w],
                     label=f"{NAMES[w]} (P = {sel[0]['P']:.0f})")
    a.axhline(etol, color="grey", ls=":", label="tolerance")
    a.invert_xaxis()
    a.set_xlabel("distance of a grid point inside the support edge (grid units)")
    a.set_ylabel("derivative (one side) max error")
    a.set_title(f"edge sensitivity, sigma = 2, tol = {etol:g}")
    a.grid(alpha=0.3)
    a.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")

# ---- tables for docs/pme_windows.md ----
def cell(w, sigma, tol):
    r = [r for r in minimal if r["window"] == w and r["sigma"] == sigma and r["tol"] == tol]
    return r[0] if r else None


print("\n### smallest P (beta/P) per window, value window, max error <= tol\n")
print("| tol | " + " | ".join(f"{NAMES[w]} s={s:g}" for s in sigmas for w in range(3)) + " |")
print("|---" * (1 + 3 * len(sigmas)) + "|")
for tol in tols:
    cells = []
    for s in sigmas:
        for w in range(3):
            r = cell(w, s, tol)
            cells.append("-" if not r or r["P"] == 0 else f"{r['P']:.0f} ({r['t']:.2f})")
    print(f"| {tol:g} | " + " | ".join(cells) + " |")

print("\n### smallest P with derivative windows (one side / both sides), value-optimal shape\n")
print("| tol | " + " | ".join(f"{NAMES[w]} s={s:g}" for s in sigmas for w in range(3)) + " |")
print("|---" * (1 + 3 * len(sigmas)) + "|")
for tol in tols:
    cells = []
    for s in sigmas:
        for w in range(3):
            r = cell(w, s, tol)
            f = lambda p: "-" if p == 0 else f"{p:.0f}"
            cells.append("-" if not r else f"{f(r['P_d1'])}/{f(r['P_d2'])}")
    print(f"| {tol:g} | " + " | ".join(cells) + " |")

print("\n### rules (least squares over tolerances with P found)\n")
for w in range(3):
    for s in sigmas:
        sel = [r for r in minimal if r["window"] == w and r["sigma"] == s and r["P"] > 0]
        if len(sel) >= 3:
            x = np.log10(1 / np.array([r["tol"] for r in sel]))
            P = np.array([r["P"] for r in sel])
            b, a = np.polyfit(x, P, 1)
            print(f"{NAMES[w]:8s} sigma {s:4g}: P = {a:.2f} + {b:.2f} log10(1/tol)"
                  f" (max residual {np.max(np.abs(a + b * x - P)):.2f}); beta/P mean {np.mean([r['t'] for r in sel]):.3f}"
                  f" range {min(r['t'] for r in sel):.3f}-{max(r['t'] for r in sel):.3f}")
    sel = [r for r in minimal if r["window"] == w and r["P"] >= 4]
    if len(sel) >= 3:
        inv = 1 / np.array([r["sigma"] for r in sel])
        t = np.array([r["t"] for r in sel])
        d, c = np.polyfit(inv, t, 1)
        print(f"{NAMES[w]:8s} beta/P = {c:.3f} + ({d:.3f}) / sigma (P >= 4; rms residual {np.sqrt(np.mean((c + d * inv - t) ** 2)):.3f})")

print("\n### measured costs\n")
for r in kind(2):
    print(f"spread+gather 3 fields P {r['P']:.0f}: c_s = {1e9 * r['c_s']:.2f} ns (spread {r['_ph']['spread']:.3f} s,"
          f" gather {r['_ph']['gather']:.3f} s, N {r['N']:.0f})")
for r in kind(3):
    print(f"FFTW {r['M']:.0f}^3: r2c {1e3 * r['_ph']['r2c']:.2f} ms, c2r {1e3 * r['_ph']['c2r']:.2f} ms,"
          f" c_f = {1e9 * r['c_f']:.3f} ns")
for r in kind(4):
    print(f"window evaluation {NAMES[int(r['window'])]}: {r['ns_per_point']:.1f} ns per point (formula),"
          f" {r.get('poly_ns_per_point', float('nan')):.2f} ns piecewise degree {r.get('degree', 0):.0f}"
          f" (max dev {r.get('poly_max_dev', float('nan')):.1e})")
for r in kind(5):
    print(f"check {r['what']:.0f} ({NAMES[int(r['window'])]}): {r['value']:.2e}")

print("\n### cost model (3D, n_max = 32): per window its cheapest sigma and P; cost relative to the best\n")
for d in (0, 1):
    print(f"\n{'value and derivative windows (both sides)' if d else 'value window'}:\n")
    print("| tol | " + " | ".join(f"rho={rho:g}: " + " / ".join(NAMES) for rho in (0.01, 0.1, 1, 10)) + " |")
    print("|---" * 5 + "|")
    for tol in tols:
        cells = []
        for rho in (0.01, 0.1, 1, 10):
            sel = {int(r["window"]): r for r in kind(6) if r["deriv"] == d and r["rho"] == rho and r["tol"] == tol}
            if not sel:
                cells.append("-")
                continue
            best = min(r["cost"] for r in sel.values())
            cells.append(" / ".join(
                f"{sel[w]['sigma']:g}, P{sel[w]['P']:.0f}, {sel[w]['cost'] / best:.2f}" if w in sel else "-" for w in range(3)))
        print(f"| {tol:g} | " + " | ".join(cells) + " |")

rule = kind(8)
if rule:
    print("\n### shape rule beta/P = a + b / sigma at the minimal P (P+1): max error / tol\n")
    print("| tol | " + " | ".join(f"{NAMES[w]} s={s:g}" for s in sigmas for w in range(3)) + " |")
    print("|---" * (1 + 3 * len(sigmas)) + "|")
    for tol in tols:
        cells = []
        for s_ in sigmas:
            for w in range(3):
                r = sorted((r for r in rule if r["window"] == w and r["sigma"] == s_ and r["tol"] == tol),
                           key=lambda r: r["P"])
                cells.append("-" if len(r) < 2 else f"{r[0]['err_max'] / tol:.2f} ({r[1]['err_max'] / tol:.2f})")
        print(f"| {tol:g} | " + " | ".join(cells) + " |")
