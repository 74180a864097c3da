#!/usr/bin/python3
"""Chart the two-sphere capture validation (bench/validate_capture.cpp, issue 18).

  (a) calibration: s_c(lambda = 0.5, gdot* = 1, theta = 0) against the force scale F0, the thesis's
      1.11915 dotted;
  (b) critical offset s_c against gdot* for each lambda (colour) and theta (marker);
  (c) global capture efficiency alpha_og against gdot*, measured (circle through theta = 0, pi/6,
      pi/3) and the thesis's fit 0.33 lambda^0.69 gdot*^-0.36 (dashed), with our own power-law fit.

With a second results file (e.g. capture_squeeze.json, the thesis's squeeze lubrication), panels (b)
and (c) also draw its critical offsets and efficiencies (open markers, thin lines), and a table
compares the two.

Prints markdown tables for docs/capture.md.
usage: plot_capture.py [RESULTS.json] [OUT.png] [OTHER.json]
(defaults bench/results/capture.json, OUT = RESULTS with .png). Debian's python3-numpy/matplotlib only.
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/capture.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = json.load(open(src))["rows"]
kind = lambda k: [r for r in rows if r["params"]["kind"] == k]
other = json.load(open(sys.argv[3])) if len(sys.argv) > 3 else None
other_rows = other["rows"] if other else []
other_name = other["benchmark"].replace("capture_", "").replace("quick_", "") if other else ""
okind = lambda k: [r for r in other_rows if r["params"]["kind"] == k]

fig, axs = plt.subplots(1, 3, figsize=(16, 4.8))
cal = sorted(kind(0), key=lambda r: r["params"]["F0"])
if cal:
    ax = axs[0]
    ax.semilogx([r["params"]["F0"] for r in cal], [r["phases"]["s_c"] for r in cal], "o")
    ax.axhline(1.11915, color="k", ls=":", label="thesis: 1.1191-1.1192")
    ax.set_xlabel(r"force scale $F_0 = 6\pi\mu L_0 U_0$ [kT/a]")
    ax.set_ylabel(r"$s_c$ ($\lambda$ = 0.5, $\dot\gamma^*$ = 1, $\theta$ = 0)")
    ax.set_title("(a) calibration of the force scale", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    print("\ncalibration\n\n| F0 [kT/a] | s_c |\n|---|---|")
    for r in cal:
        print(f"| {r['params']['F0']:.5g} | {r['phases']['s_c']:.5f} |")

sc = kind(1)
lams = sorted({r["params"]["lambda"] for r in sc})
ths = sorted({r["params"]["theta"] for r in sc})
marks = ["o", "s", "^", "v", "D"]
print("\ncritical offsets s_c\n\n| lambda | gdot* | " + " | ".join(f"theta = {t:.4f}" for t in ths) + " |")
print("|---|---|" + "---|" * len(ths))
for i, lam in enumerate(lams):
    for j, th in enumerate(ths):
        pts = sorted((r["params"]["gdot"], r["phases"]["s_c"]) for r in sc
                     if r["params"]["lambda"] == lam and r["params"]["theta"] == th)
        axs[1].semilogx([p[0] for p in pts], [p[1] for p in pts], marks[j % 5] + "-", color=f"C{i}",
                        label=rf"$\lambda$ = {lam:g}, $\theta$ = {th:.2f}")
    for g in sorted({r["params"]["gdot"] for r in sc if r["params"]["lambda"] == lam}):
        vals = [next((r["phases"]["s_c"] for r in sc if r["params"]["lambda"] == lam and r["params"]["gdot"] == g
                      and r["params"]["theta"] == th), float("nan")) for th in ths]
        print(f"| {lam:g} | {g:g} | " + " | ".join(f"{v:.4f}" for v in vals) + " |")
for i, lam in enumerate(lams):
    for j, th in enumerate(ths):
        pts = sorted((r["params"]["gdot"], r["phases"]["s_c"]) for r in okind(1)
                     if r["params"]["lambda"] == lam and r["params"]["theta"] == th)
        if pts:
            axs[1].semilogx([p[0] for p in pts], [p[1] for p in pts], marks[j % 5] + "-", color=f"C{i}", mfc="none",
                            lw=0.6, alpha=0.8)
if other:
    axs[1].plot([], [], "ko", mfc="none", lw=0.6, label=f"open: {other_name}")
axs[1].set_xlabel(r"$\dot\gamma^* = \dot\gamma L_0/U_0$")
axs[1].set_ylabel(r"critical offset $s_c$ [$L_0$]")
axs[1].set_title(r"(b) critical offset (per-sphere, $\theta$ from the y axis)", fontsize=10)
axs[1].legend(fontsize=6, ncol=2)
axs[1].grid(alpha=0.3)

eff = kind(2)
fit = kind(3)
print("\ncapture efficiency\n\n| lambda | gdot* | R | alpha_o | alpha_og | thesis fit | ratio |\n|---|---|---|---|---|---|---|")
for i, lam in enumerate(sorted({r["params"]["lambda"] for r in eff})):
    pts = sorted((r["params"]["gdot"], r["phases"]["alpha_og"], r["phases"]["thesis_fit"], r["phases"]["R"],
                  r["phases"]["alpha_o"]) for r in eff if r["params"]["lambda"] == lam)
    g = np.array([p[0] for p in pts])
    axs[2].loglog(g, [p[1] for p in pts], "o-", color=f"C{i}", label=(rf"exact, $\lambda$ = {lam:g}" if other else rf"measured, $\lambda$ = {lam:g}"))
    axs[2].loglog(g, [p[2] for p in pts], "--", color=f"C{i}", alpha=0.7)
    if fit:
        c, k1, k2 = (fit[0]["phases"][k] for k in ("c", "k1", "k2"))
        axs[2].loglog(g, c * lam ** k1 * g ** k2, ":", color=f"C{i}")
    for p in pts:
        print(f"| {lam:g} | {p[0]:g} | {p[3]:.4f} | {p[4]:.4f} | {p[1]:.4f} | {p[2]:.4f} | {p[1] / p[2]:.3f} |")
if fit:
    c, k1, k2 = (fit[0]["phases"][k] for k in ("c", "k1", "k2"))
    print(f"\nfit: alpha_og = {c:.4f} lambda^{k1:.3f} gdot*^{k2:.3f} (thesis 0.33 lambda^0.69 gdot*^-0.36)")
    axs[2].plot([], [], "k:", label=rf"our fit {c:.3f} $\lambda^{{{k1:.2f}}}\dot\gamma^{{*{k2:.2f}}}$")
axs[2].plot([], [], "k--", label=r"thesis 0.33 $\lambda^{0.69}\dot\gamma^{*-0.36}$")
if other:
    oeff = okind(2)
    print(f"\n{other_name} against this run: alpha_og\n\n| lambda | gdot* | this run | {other_name} | ratio | thesis fit |"
          "\n|---|---|---|---|---|---|")
    all_lams = sorted({r["params"]["lambda"] for r in eff})
    for lam in sorted({r["params"]["lambda"] for r in oeff}):
        i = all_lams.index(lam) if lam in all_lams else len(all_lams)
        pts = sorted((r["params"]["gdot"], r["phases"]["alpha_og"]) for r in oeff if r["params"]["lambda"] == lam)
        axs[2].loglog([p[0] for p in pts], [p[1] for p in pts], "s-", color=f"C{i}", mfc="none", lw=0.6)
        for g, a in pts:
            mine = next((r["phases"]["alpha_og"] for r in eff if r["params"]["lambda"] == lam and r["params"]["gdot"] == g),
                        float("nan"))
            print(f"| {lam:g} | {g:g} | {mine:.4f} | {a:.4f} | {a / mine:.3f} | {0.33 * lam ** 0.69 * g ** -0.36:.4f} |")
    axs[2].plot([], [], "ks-", mfc="none", lw=0.6, label=f"{other_name}")
    for r in okind(0)[-1:]:
        print(f"\n{other_name}: last calibration step F0 = {r['params']['F0']:.5g}, s_c = {r['phases']['s_c']:.5f}")
    for r in okind(3):
        print(f"{other_name} fit: alpha_og = {r['phases']['c']:.4f} lambda^{r['phases']['k1']:.3f} "
              f"gdot*^{r['phases']['k2']:.3f}")
axs[2].set_xlabel(r"$\dot\gamma^*$")
axs[2].set_ylabel(r"global capture efficiency $\alpha_{o,g}$")
axs[2].set_title("(c) capture efficiency against the thesis's fit" + (f" (open: {other_name})" if other else ""),
                 fontsize=10)
axs[2].legend(fontsize=7)
axs[2].grid(alpha=0.3, which="both")
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"\nwrote {out}")
