#!/usr/bin/python3
"""Chart the constrained-SD cost benchmark (bench/bench_channel.cpp, issue 17; Lee et al. 2024
fig. 6): (a) wall time per Brownian SD step against N for the dense and the accelerated solver at
interior fractions 1, 0.1, 0.01 in simple shear (as [L24]), and for the dense solver also without
the shear ("still", where the held block's factor is kept), with the exponent of a least-squares
fit of log t against log N; (b) the speed-up from the constraint, t(fraction 1) / t(fraction f) at
the same N; (c) where an accelerated-SD step's time goes (the solver's named phases, when the
results have them): GMRES (products, triangular solves, preconditioner), far-field noise (Lanczos),
near-field noise, set-up (far field, near field, factorisation, held blocks), at each N and
fraction, with the GMRES iterations per step above each bar. Prints the table of
docs/benchmarks.md.

usage: plot_channel.py [RESULTS.json] [OUT.png]   (default bench/results/channel.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/channel.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = json.load(open(src))["rows"]
names = {(0, 1): "dense SD", (0, 0): "dense SD, still", (1, 1): "accelerated SD"}
styles = ((0, 1, "s", "--"), (0, 0, "D", ":"), (1, 1, "o", "-"))


def series(r):
    return (int(r["params"]["solver"]), int(r["params"].get("shear", 1)))

fracs = sorted({r["params"]["fraction"] for r in rows}, reverse=True)

asd_phases = [r for r in rows if int(r["params"]["solver"]) == 1 and "krylov" in r["phases"]]
fig, ax = plt.subplots(1, 3 if asd_phases else 2, figsize=(18 if asd_phases else 12, 4.8))
table = {}
for solver, shear, marker, ls in styles:
    s = (solver, shear)
    for k, f in enumerate(fracs):
        pts = sorted([r for r in rows if series(r) == s and r["params"]["fraction"] == f],
                     key=lambda r: r["params"]["N"])
        if not pts:
            continue
        n = np.array([r["params"]["N"] for r in pts])
        t = np.array([r["phases"]["seconds"] for r in pts])
        for r in pts:
            table[(s, f, int(r["params"]["N"]))] = r["phases"]["seconds"]
        slope = np.polyfit(np.log(n), np.log(t), 1)[0] if len(n) > 1 else float("nan")
        print(f"{names[s]}, interior fraction {f:g}: exponent {slope:.2f} over N = {int(n.min())}..{int(n.max())}")
        ax[0].loglog(n, t, marker=marker, ls=ls, color=f"C{k}",
                     label=f"{names[s]}, N_I/N = {f:g} (slope {slope:.2f})")
ax[0].set_xlabel("N = N_I + N_W")
ax[0].set_ylabel("wall time per Brownian step [s]")
ax[0].set_title("(a) constrained SD, φ = 0.2, Pe = 1 (still: 0), FT, tol 1e-3")
ax[0].legend(fontsize=8)
ax[0].grid(alpha=0.3, which="both")

print("solver, N, t(1) s, speed-up at 0.1, at 0.01")
for solver, shear, marker, ls in styles:
    s = (solver, shear)
    for k, f in enumerate(fracs[1:], start=1):
        ns = sorted({N for (ss, ff, N) in table if ss == s and ff == f and (s, 1.0, N) in table})
        if not ns:
            continue
        ax[1].loglog(ns, [table[(s, 1.0, N)] / table[(s, f, N)] for N in ns], marker=marker, ls=ls, color=f"C{k}",
                     label=f"{names[s]}, N_I/N = {f:g}")
    for N in sorted({N for (ss, ff, N) in table if ss == s and ff == 1.0}):
        sp = [table[(s, 1.0, N)] / table[(s, f, N)] if (s, f, N) in table else float("nan") for f in fracs[1:]]
        print(f"  {names[s]:17s} {N:6d} {table[(s, 1.0, N)]:.3g} " + " ".join(f"{v:.2f}" for v in sp))
ax[1].axhline(1.0, color="0.6", lw=0.8)
ax[1].set_xlabel("N")
ax[1].set_ylabel("t(N_I/N = 1) / t(N_I/N)")
ax[1].set_title("(b) speed-up from the constraint")
ax[1].legend(fontsize=8)
ax[1].grid(alpha=0.3, which="both")
if asd_phases:
    parts = (("krylov", "GMRES solves"), ("far_noise", "far-field noise (Lanczos)"), ("near_noise", "near-field noise"),
             ("setup", "set-up (far, near, factor, held blocks)"), ("other", "rest of the step"))
    ns = sorted({int(r["params"]["N"]) for r in asd_phases})
    width = 0.8 / len(fracs)
    print("accelerated SD per step: N, fraction, seconds, GMRES its, krylov, far noise, near noise, set-up")
    for k, f in enumerate(fracs):
        for i, N in enumerate(ns):
            r = next((r for r in asd_phases if int(r["params"]["N"]) == N and r["params"]["fraction"] == f), None)
            if r is None:
                continue
            p = r["phases"]
            setup = p["far_field_setup"] + p["near_field_assembly"] + p["factorisation"] + p["held_preconditioner"]
            val = {"krylov": p["krylov"], "far_noise": p["far_noise"], "near_noise": p["near_noise"], "setup": setup}
            val["other"] = max(0.0, p["seconds"] - sum(val.values()))
            x = i + (k - (len(fracs) - 1) / 2) * width
            bottom = 0.0
            for j, (key, label) in enumerate(parts):
                frac_t = val[key] / p["seconds"]
                ax[2].bar(x, frac_t, width * 0.9, bottom=bottom, color=f"C{j + 3}",
                          label=label if (k == 0 and i == 0) else None, edgecolor="k" if f == 1.0 else "none", lw=0.5)
                bottom += frac_t
            ax[2].text(x, 1.01, f"{p['gmres_iterations']:.0f}", ha="center", va="bottom", fontsize=7)
            print(f"  {N:6d} {f:5g} {p['seconds']:.4f} {p['gmres_iterations']:5.1f} {p['krylov']:.4f} {p['far_noise']:.4f} "
                  f"{p['near_noise']:.4f} {setup:.4f}")
    ax[2].set_xticks(range(len(ns)))
    ax[2].set_xticklabels([f"{N}\n" + " ".join(f"{f:g}" for f in fracs) for N in ns], fontsize=8)
    ax[2].set_xlabel("N, and the bars' N_I/N (left to right)")
    ax[2].set_ylabel("share of the step's wall time")
    ax[2].set_ylim(0, 1.12)
    ax[2].set_title("(c) accelerated SD: shares of a step (GMRES iterations on top)")
    ax[2].legend(fontsize=7, loc="lower left")
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
