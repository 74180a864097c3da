#!/usr/bin/python3
"""Chart the channel validation (bench/validate_slit.cpp, issue 17): (a) mobility of a sphere beside
one plane wall of wall particles, parallel and perpendicular, against the gap h, with Faxen's and
Brenner's flat-wall series; (b) the same in a slit of height 32 a against two flat planes (their
point-force reflection plus each wall's finite-size terms, computed by the driver) and, dashed, the
two walls' series superposed;
(c) short-time self-diffusivity D_par/D0 and D_perp/D0 across a 6 a slit at each volume fraction,
binned by the centre height (error bars: one standard error of the bin mean), and, where given, the
same from the mean-square displacement of Brownian runs at the shortest lag (tools/stokesian_msd.py
--json; its meta "phi" names the volume fraction). Prints the tables of docs/channels.md.

usage: plot_slit.py [RESULTS.json] [OUT.png] [MSD.json]
       (defaults bench/results/slit.json and, with it, bench/results/slit_msd.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/slit.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
msd_src = sys.argv[3] if len(sys.argv) > 3 else ("bench/results/slit_msd.json" if len(sys.argv) <= 1 else None)
rows = json.load(open(src))["rows"]
mob = [r for r in rows if r["params"]["kind"] == 0]
dif = [r for r in rows if r["params"]["kind"] == 1]
flat = sorted([r for r in rows if r["params"]["kind"] == 3], key=lambda r: r["params"]["h"])

fig, ax = plt.subplots(1, 3, figsize=(16, 4.8))
for geo, a, title in ((0, ax[0], "(a) one plane wall (patch 80 a)"), (1, ax[1], "(b) slit H = 32 a (patches 64 a)")):
    pts = sorted([r for r in mob if r["params"]["geometry"] == geo], key=lambda r: r["params"]["h"])
    if not pts:
        a.set_visible(False)
        continue
    h = np.array([r["params"]["h"] for r in pts])
    print(f"{'plane' if geo == 0 else 'slit'}: h, parallel, flat, dev %, perpendicular, flat, dev %"
          + ("; superposed parallel, perpendicular" if geo == 1 else ""))
    for r in pts:
        p = r["phases"]
        print(f"  {r['params']['h']:5.2f}  {p['par']:.4f} {p['par_ref']:.4f} {100 * (p['par'] / p['par_ref'] - 1):+6.1f}"
              f"  {p['perp']:.4f} {p['perp_ref']:.4f} {100 * (p['perp'] / p['perp_ref'] - 1):+6.1f}"
              + (f";  {p['par_sup']:.4f} {p['perp_sup']:.4f}" if geo == 1 else ""))
    # The single wall's series on a fine grid (same formulas as the driver); the slit's flat-plane
    # references come from the driver (kind 3 rows).
    hh = np.geomspace(max(h.min(), 0.05), h.max(), 200)
    z1 = 1.0 + hh
    z2 = 32.0 - z1 if geo == 1 else np.full_like(hh, np.inf)
    faxen = lambda x: 1 - 9 / 16 * x + x**3 / 8 - 45 / 256 * x**4 - x**5 / 16
    brenner = lambda x: 1 - 9 / 8 * x + 0.5 * x**3
    sup = {"par": faxen(1 / z1) + faxen(1 / z2) - 1, "perp": brenner(1 / z1) + brenner(1 / z2) - 1}
    for key, c, lab in (("par", "C0", "parallel"), ("perp", "C3", "perpendicular")):
        a.plot(h, [r["phases"][key] for r in pts], "o", color=c, label=f"{lab}, wall particles")
        if geo == 0:
            a.plot(hh, sup[key], "-", color=c, label=f"{lab}, flat-wall series")
        else:
            a.plot([r["params"]["h"] for r in flat], [r["phases"][key + "_ref"] for r in flat], "-", color=c,
                   label=f"{lab}, two flat planes")
            a.plot(hh, sup[key], "--", color=c, lw=0.8, label=f"{lab}, single walls superposed")
    a.axvline(3.0, color="0.7", ls=":")
    a.set_xscale("log")
    a.set_xlabel("gap h / a (sphere surface to the walls' boundary plane)")
    a.set_ylabel("mobility × 6πμa")
    a.set_title(title)
    a.legend(fontsize=8)
    a.grid(alpha=0.3)

a = ax[2]
phis = sorted({r["params"]["phi"] for r in dif})
H = 6.0
edges = np.linspace(-H / 2 + 1, H / 2 - 1, 9)
print("diffusion: phi, bin centre eta/a, n, D_par/D0 (se), D_perp/D0 (se)")
for k, phi in enumerate(phis):
    pts = [r for r in dif if r["params"]["phi"] == phi]
    eta = np.array([r["params"]["eta"] for r in pts])
    dp = np.array([r["phases"]["Dpar"] for r in pts])
    dn = np.array([r["phases"]["Dperp"] for r in pts])
    # Fold the two halves of the slit together (the problem is symmetric about the centre).
    y = np.abs(eta)
    fedges = np.linspace(0.0, H / 2 - 1 + 1e-9, 6)
    cen, mp, sp, mn, sn = [], [], [], [], []
    for lo, hi in zip(fedges[:-1], fedges[1:]):
        m = (y >= lo) & (y < hi)
        if m.sum() < 2:
            continue
        cen.append(0.5 * (lo + hi))
        mp.append(dp[m].mean()); sp.append(dp[m].std(ddof=1) / np.sqrt(m.sum()))
        mn.append(dn[m].mean()); sn.append(dn[m].std(ddof=1) / np.sqrt(m.sum()))
        print(f"  {phi:.2f} {0.5 * (lo + hi):4.2f} {m.sum():4d}  {mp[-1]:.3f} ({sp[-1]:.3f})  {mn[-1]:.3f} ({sn[-1]:.3f})")
    c = f"C{k}"
    a.errorbar(cen, mp, yerr=sp, fmt="o-", color=c, label=f"D∥, φ = {phi:g}")
    a.errorbar(cen, mn, yerr=sn, fmt="s--", color=c, mfc="white", label=f"D⊥, φ = {phi:g}")
if msd_src:
    msd = json.load(open(msd_src))
    phi = msd["meta"]["phi"]
    lag = min(r["lag_frames"] for r in msd["rows"])
    pts = [r for r in msd["rows"] if r["lag_frames"] == lag and "D" in r]
    c = f"C{phis.index(phi)}" if phi in phis else "k"
    cen = [0.5 * (r["bin"][0] + r["bin"][1]) + 0.04 for r in pts]
    a.errorbar(cen, [0.5 * (r["D"][0] + r["D"][2]) for r in pts],
               yerr=[0.5 * np.hypot(r["se"][0], r["se"][2]) for r in pts], fmt="^", color=c, ms=5,
               label=f"D∥, φ = {phi:g}, Brownian MSD")
    a.errorbar(cen, [r["D"][1] for r in pts], yerr=[r["se"][1] for r in pts], fmt="v", color=c, mfc="white", ms=5,
               label=f"D⊥, φ = {phi:g}, Brownian MSD")
a.set_xlabel("|y − c_y| / a (0: slit centre; 2: touching a wall)")
a.set_ylabel("D / D0")
a.set_title("(c) self-diffusivity across a 6 a slit (accelerated SD, FTS)")
lo, hi = a.get_ylim()
a.set_ylim(lo, hi + 0.3 * (hi - lo))  # room for the legend above the data
a.legend(fontsize=7.5, ncol=3, loc="upper center")
a.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
