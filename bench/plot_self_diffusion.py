#!/usr/bin/python3
"""Chart the short-time self-diffusion validation (bench/validate_diffusion.cpp, issue 13):
(a) D_s0/D0 against phi: the finite-N points (N = 100 ... 800, small markers), the values
extrapolated to N -> infinity (linear in a/L, error bars = one standard error of the intercept)
and the fit of Abade et al., J. Chem. Phys. 132, 014503 (2010), 1 - 1.8315 phi (1 + 0.12 phi -
0.70 phi^2), with its +-5 % band (the issue's goal); (b) D_s/D0 against a/L per phi with the
fitted lines and, dashed, the slope -2.837297 mu/eta_inf' of Ladd's finite-size law (eta_inf' from
the generalised Saito form) drawn through the extrapolated value. Prints the table of
docs/benchmarks.md, with the intercept's standard error scaled by sqrt(chi2/dof) where that
exceeds 1 and, as a check of the linear law, the intercept of the fit without the smallest N.

usage: plot_self_diffusion.py [RESULTS.json] [OUT.png]   (default bench/results/self_diffusion.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/self_diffusion.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
finite = [r for r in rows if r["params"]["kind"] == 0]
extra = sorted([r for r in rows if r["params"]["kind"] == 1], key=lambda r: r["params"]["phi"])
phis = [r["params"]["phi"] for r in extra]
sizes = sorted({r["params"]["N"] for r in finite})


def abade(phi):
    return 1.0 - 1.8315 * phi * (1.0 + 0.12 * phi - 0.70 * phi**2)


fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5))
grid = np.linspace(0.0, 0.5, 200)
ax.plot(grid, abade(grid), "k-", label="Abade et al. 2010 fit")
ax.fill_between(grid, 0.95 * abade(grid), 1.05 * abade(grid), color="0.85", label="fit $\\pm$5 %")
markers = {100: "v", 200: "^", 400: "s", 800: "D", 50: "<"}
cmap = plt.get_cmap("viridis")
for k, n in enumerate(sizes):
    pts = sorted([r for r in finite if r["params"]["N"] == n], key=lambda r: r["params"]["phi"])
    ax.errorbar([r["params"]["phi"] for r in pts], [r["phases"]["D"] for r in pts],
                yerr=[r["phases"]["se"] for r in pts], fmt=markers.get(int(n), "o"), ms=4, capsize=2,
                color=cmap(0.15 + 0.7 * k / max(1, len(sizes) - 1)), label=f"N = {int(n)}")
ax.errorbar(phis, [r["phases"]["D_inf"] for r in extra], yerr=[r["phases"]["se_inf"] for r in extra],
            fmt="o", color="tab:red", ms=7, capsize=4, label="extrapolated N $\\to\\infty$")
ax.set_xlabel("volume fraction $\\phi$")
ax.set_ylabel("$D_s^0 / D_0$")
ax.set_xlim(0, 0.5)
ax.set_ylim(0, 1.05)
ax.set_title("Short-time self-diffusion, accelerated SD (FTS, PME)")
ax.legend(fontsize=8)

colors = plt.get_cmap("tab10")
for k, e in enumerate(extra):
    phi = e["params"]["phi"]
    pts = sorted([r for r in finite if abs(r["params"]["phi"] - phi) < 1e-9], key=lambda r: r["params"]["L"])
    x = np.array([1.0 / r["params"]["L"] for r in pts])
    bx.errorbar(x, [r["phases"]["D"] for r in pts], yerr=[r["phases"]["se"] for r in pts], fmt="o", ms=4,
                capsize=2, color=colors(k), label=f"$\\phi$ = {phi:g}")
    xx = np.linspace(0, x.max() * 1.05, 20)
    p = e["phases"]
    bx.plot(xx, p["D_inf"] + p["slope"] * xx, "-", color=colors(k), lw=1)
    bx.plot(xx, p["D_inf"] + p["slope_ladd"] * xx, "--", color=colors(k), lw=0.8)
    bx.errorbar([0], [p["D_inf"]], yerr=[p["se_inf"]], fmt="*", ms=9, color=colors(k), capsize=3)
    bx.plot([0], [abade(phi)], "kx", ms=7)
bx.plot([], [], "k-", lw=1, label="weighted fit")
bx.plot([], [], "k--", lw=0.8, label="Ladd slope $-2.837\\,\\mu/\\eta_\\infty'$")
bx.plot([], [], "kx", label="Abade fit")
bx.set_xlabel("$a / L$")
bx.set_ylabel("$D_s / D_0$")
bx.set_xlim(left=-0.003)
bx.set_ylim(0.0, 0.86)
bx.set_title("finite-size extrapolation")
bx.legend(fontsize=8, ncol=2, loc="lower left")
m = data.get("machine", {})
fig.suptitle(f"validate_diffusion, git {m.get('git', '?')}, {m.get('date', '')}", fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")



def wfit(x, y, se):
    """Weighted straight line y = b0 + b1 x: (b0, se b0)."""
    w = 1.0 / np.asarray(se) ** 2
    A = np.vstack([np.ones_like(x), x]).T
    cov = np.linalg.inv(A.T @ (A * w[:, None]))
    b = cov @ (A.T @ (w * np.asarray(y)))
    return b[0], np.sqrt(cov[0, 0])


print("| phi | N = " + " | N = ".join(str(int(n)) for n in sizes) +
      " | extrapolated (se x max(1, sqrt(chi2/dof))) | Abade fit | rel. error | without smallest N |"
      " slope per a/L | Ladd slope | chi2/dof |")
print("|---" * (len(sizes) + 8) + "|")
for e in extra:
    phi = e["params"]["phi"]
    cells = []
    for n in sizes:
        r = [r for r in finite if abs(r["params"]["phi"] - phi) < 1e-9 and r["params"]["N"] == n]
        cells.append(f"{r[0]['phases']['D']:.4f} ± {r[0]['phases']['se']:.4f}" if r else "")
    p = e["phases"]
    pts = sorted([r for r in finite if abs(r["params"]["phi"] - phi) < 1e-9], key=lambda r: r["params"]["N"])[1:]
    # The fit without the smallest box needs two boxes left (the quick form runs only two).
    if len(pts) >= 2:
        b0, s0 = wfit(np.array([1.0 / r["params"]["L"] for r in pts]), [r["phases"]["D"] for r in pts],
                      [r["phases"]["se"] for r in pts])
        without = f"{b0:.4f} ± {s0:.4f} ({100 * (b0 - p['fit']) / p['fit']:+.1f} %)"
    else:
        without = "n/a (fewer than three box sizes)"
    se_scaled = p["se_inf"] * max(1.0, np.sqrt(p["chi2"]))
    print(f"| {phi:g} | " + " | ".join(cells) +
          f" | {p['D_inf']:.4f} ± {se_scaled:.4f} | {p['fit']:.4f} | {100 * p['rel_err']:+.1f} % |"
          f" {without} |"
          f" {p['slope']:.2f} ± {p['se_slope']:.2f} | {p['slope_ladd']:.2f} | {p['chi2']:.2f} |")
