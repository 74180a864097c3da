#!/usr/bin/python3
"""Chart the fouling runs (bench/fouling_summary.py; issue 17, docs/channels.md "Fouling runs"):
for each run, against time, (a) the particle pressure drop pressure_drop_particles (and, for outlines
of several branches such as the T-junction, means over windows of 10 time units of the total and of
pressure_drop_branches), (b) the areal fraction of the whole channel, of its most and least occupied
sections along x and of each branch, (c) the spheres
deposited on the walls and the particles present, inserted and removed, (d) the last frame.

usage: plot_fouling.py [RESULTS.json] [OUT.png]   (default bench/results/fouling.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/fouling.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
runs = json.load(open(src))["runs"]

fig, ax = plt.subplots(len(runs), 4, figsize=(20, 4.2 * len(runs)), squeeze=False)
for row, (name, r) in enumerate(runs.items()):
    s = r["series"]
    t = np.array(s["time"])
    dp = np.array(s["pressure_drop_particles"])
    a = ax[row]
    branch_dp = np.array(s.get("pressure_drop_branches", []))
    branch_areal = np.array(s.get("areal_fraction_branches", []))
    several = branch_dp.ndim == 2 and branch_dp.shape[1] > 1
    a[0].plot(t, dp, ".-", color="0.75" if several else "C0", lw=0.8, label="pressure_drop_particles (frames)")
    if several:
        # Means over windows of 10 time units: the total and each branch (branch 0 holds the inlet).
        edges = np.arange(0.5, t[-1] + 10, 10.0)
        mid = 0.5 * (edges[:-1] + edges[1:])
        def windows(y):
            return np.array([y[(t >= lo) & (t < hi)].mean() if np.any((t >= lo) & (t < hi)) else np.nan
                             for lo, hi in zip(edges[:-1], edges[1:])])
        a[0].plot(mid, windows(dp), "k-", lw=2, label="total, means over 10 t")
        names = ["main (branch 0)", "side (branch 1)"] + [f"branch {b}" for b in range(2, branch_dp.shape[1])]
        for b in range(branch_dp.shape[1]):
            a[0].plot(mid, windows(branch_dp[:, b]), f"C{b}-", lw=2, label=f"{names[b]}, means over 10 t")
        a[0].legend(fontsize=8)
    a[0].axhline(0, color="0.6", lw=0.8)
    a[0].set_ylabel("particle pressure drop [kT/a³]")
    # The first frame holds the start's transient (spheres being pulled onto the walls); its value
    # is written beside the axis when it is off the scale of the rest.
    if len(dp) > 2 and abs(dp[0]) > 3 * np.max(np.abs(dp[1:])):
        a[0].set_ylim(1.3 * min(0, dp[1:].min()), 1.3 * dp[1:].max())
        a[0].annotate(f"t = 0: {dp[0]:.3g}", xy=(0.02, 0.04), xycoords="axes fraction")
    sec = np.array(s["areal_fraction_sections"])
    a[1].plot(t, sec.mean(axis=1), "k-", label="mean over the sections")
    a[1].plot(t, sec.max(axis=1), "C3--", label="most occupied section")
    a[1].plot(t, sec.min(axis=1), "C2:", label="least occupied section")
    if several:
        for b in range(branch_areal.shape[1]):
            a[1].plot(t, branch_areal[:, b], f"C{b}-", lw=1.5, label=names[b])
    a[1].set_ylabel("areal fraction")
    a[1].legend(fontsize=8)
    a[2].plot(t, s["deposited"], "C1.-", label=f"deposited (gap < {r['contact_gap']} a to a wall)")
    a[2].plot(t, s["particles_present"], "C0-", label="present")
    a[2].plot(t, s["inflow_inserted"], "C2--", label="inserted (total)")
    a[2].plot(t, s["inflow_removed"], "C3:", label="removed (total)")
    a[2].set_ylabel("particles")
    a[2].legend(fontsize=8)
    for k in range(3):
        a[k].set_xlabel("t [a / u_avg]")
        a[k].set_title(f"{name} (to t = {r['last_time']:.3g})", fontsize=10)
    # The last frame: wall particles grey, spheres deposited on a wall orange, the others blue.
    snap = r["snapshot"]
    xs, ys, rs, wall = (np.array(snap[k]) for k in ("x", "y", "radius", "wall"))
    walls = np.c_[xs[wall], ys[wall]]
    for xi, yi, ri, w in zip(xs, ys, rs, wall):
        if w:
            color = "0.7"
        else:
            gap = np.min(np.hypot(*(walls - [xi, yi]).T) - ri - rs[wall]) if len(walls) else 1.0
            color = "C1" if gap < r["contact_gap"] else "C0"
        a[3].add_patch(plt.Circle((xi, yi), ri, color=color, lw=0))
    a[3].set_xlim(xs.min() - 2, xs.max() + 2)
    a[3].set_ylim(ys.min() - 2, ys.max() + 2)
    a[3].set_aspect("equal")
    a[3].set_title(f"{name} at t = {r['last_time']:.3g} (orange: deposited)", fontsize=10)
    a[3].set_xlabel("x [a]")
    a[3].set_ylabel("y [a]")
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
