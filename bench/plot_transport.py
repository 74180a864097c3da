#!/usr/bin/python3
"""Chart the transport validation (bench/validate_transport.cpp, issue 15): (a) the high-frequency
dynamic viscosity eta'_inf/mu against phi at each N (error bars = one standard error over
configurations) with the fit 1 + 2.5 phi (1+S)/(1 - phi (1+S)), S = phi (1 + 0.95 phi - 2.15 phi^2);
(b) the sedimentation coefficient K against phi, raw at each N (open markers) and with Ladd's
finite-size correction + 2.837297 (a/L) S(0) mu/eta'_inf (filled), with the fit
1 - 6.5464 phi (1 - 3.348 phi + 7.426 phi^2 - 10.034 phi^3 + 5.882 phi^4), log scale; (c) the
ratio SD / fit of both. Fits: Abade et al. (hydromultipole data), forms as in Riest et al. 2015
(docs/transport.md). Prints the table of docs/transport.md.

usage: plot_transport.py [RESULTS.json] [OUT.png]   (default bench/results/transport.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/transport.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
sizes = sorted({int(r["params"]["N"]) for r in rows})
phis = sorted({r["params"]["phi"] for r in rows})


def eta_fit(phi):
    s = phi * (1.0 + 0.95 * phi - 2.15 * phi**2)
    return 1.0 + 2.5 * phi * (1.0 + s) / (1.0 - phi * (1.0 + s))


def k_fit(phi):
    return 1.0 - 6.5464 * phi * (1.0 - 3.348 * phi + 7.426 * phi**2 - 10.034 * phi**3 + 5.882 * phi**4)


def series(n):
    pts = sorted([r for r in rows if int(r["params"]["N"]) == n], key=lambda r: r["params"]["phi"])
    return (np.array([r["params"]["phi"] for r in pts]), {k: np.array([r["phases"][k] for r in pts])
                                                          for k in pts[0]["phases"]})


fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(16, 5))
grid = np.linspace(0.0, 0.52, 200)
cmap = plt.get_cmap("viridis")
colors = {n: cmap(0.1 + 0.75 * k / max(1, len(sizes) - 1)) for k, n in enumerate(sizes)}
dx = {n: (k - (len(sizes) - 1) / 2) * 0.004 for k, n in enumerate(sizes)}  # spread markers apart

ax.plot(grid, eta_fit(grid), "k-", label="fit (Abade et al. data)")
ax.fill_between(grid, 0.97 * eta_fit(grid), 1.03 * eta_fit(grid), color="0.85", label="fit $\\pm$3 %")
for n in sizes:
    x, p = series(n)
    ax.errorbar(x + dx[n], p["eta"], yerr=p["se_eta"], fmt="o", ms=4, capsize=2, color=colors[n], label=f"SD, N = {n}")
ax.set_xlabel("volume fraction $\\phi$")
ax.set_ylabel("$\\eta'_\\infty / \\mu$")
ax.set_xlim(0, 0.52)
ax.set_ylim(1, 9)
ax.set_title("high-frequency dynamic viscosity")
ax.legend(fontsize=8)

bx.semilogy(grid[1:], k_fit(grid[1:]), "k-", label="fit (Abade et al. data)")
for n in sizes:
    x, p = series(n)
    bx.errorbar(x + dx[n], p["K"], yerr=p["se_K"], fmt="o", mfc="none", ms=4, capsize=2, color=colors[n],
                label=f"SD raw, N = {n}")
    bx.errorbar(x + dx[n], p["K_inf"], yerr=p["se_K"], fmt="o", ms=4, capsize=2, color=colors[n],
                label=f"SD + finite-size term, N = {n}")
bx.set_xlabel("volume fraction $\\phi$")
bx.set_ylabel("$K = U_{sed} / U_0$")
bx.set_xlim(0, 0.52)
bx.set_ylim(0.02, 1.05)
bx.set_title("sedimentation coefficient (zero-volume-flux frame)")
bx.legend(fontsize=7)

for n in sizes:
    x, p = series(n)
    cx.errorbar(x + dx[n], p["eta"] / eta_fit(x), yerr=p["se_eta"] / eta_fit(x), fmt="s", ms=4, capsize=2,
                color=colors[n], label=f"$\\eta'_\\infty$, N = {n}")
    cx.errorbar(x + dx[n], p["K_inf"] / k_fit(x), yerr=p["se_K"] / k_fit(x), fmt="^", ms=5, capsize=2,
                color=colors[n], label=f"K (corrected), N = {n}")
cx.axhline(1.0, color="k", lw=0.8)
cx.set_yscale("log")
cx.set_xlabel("volume fraction $\\phi$")
cx.set_ylabel("SD / fit")
cx.set_xlim(0, 0.52)
cx.set_title("ratio to the fits")
cx.legend(fontsize=7, ncol=2)
m = data.get("machine", {})
fig.suptitle(f"validate_transport (accelerated SD, FTS, PME, periodic), git {m.get('git', '?')}, {m.get('date', '')}",
             fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")

print("| φ | N | configs | η′∞/μ ± se | fit | dev. | K ± se (raw) | + finite-size term | K corrected | fit | dev. |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for phi in phis:
    for n in sizes:
        r = [r for r in rows if abs(r["params"]["phi"] - phi) < 1e-9 and int(r["params"]["N"]) == n]
        if not r:
            continue
        p, q = r[0]["params"], r[0]["phases"]
        print(f"| {phi:g} | {n} | {int(p['configs'])} | {q['eta']:.4f} ± {q['se_eta']:.4f} | {q['eta_fit']:.4f} |"
              f" {100 * (q['eta'] / q['eta_fit'] - 1):+.1f} % | {q['K']:.4f} ± {q['se_K']:.4f} | {q['correction']:+.4f} |"
              f" {q['K_inf']:.4f} | {q['K_fit']:.4f} | {100 * (q['K_inf'] / q['K_fit'] - 1):+.1f} % |")
