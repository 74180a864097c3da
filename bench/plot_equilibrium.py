#!/usr/bin/python3
"""Chart the Brownian equilibrium validation (issue 13, bench/validate_equilibrium.cpp): sampled
histograms of the observable (dimer centre distance r; wall height z above z_full) with and
without the thermal drift, against the Boltzmann density, with the Kolmogorov-Smirnov p-values.

usage: plot_equilibrium.py [RESULTS.json] [OUT.png]   (default: bench/results/equilibrium.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/equilibrium.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
runs = data["runs"]
scenes = [s for s in ("dimer", "wall") if any(r["scene"] == s for r in runs)]

fig, axes = plt.subplots(1, len(scenes), figsize=(6.5 * len(scenes), 4.8), squeeze=False)
for ax, scene in zip(axes[0], scenes):
    ref = None
    for r in runs:
        if r["scene"] != scene:
            continue
        e = np.array(r["edges"])
        c = 0.5 * (e[1:] + e[:-1])
        label = (f"{'with' if r['drift'] else 'without'} drift: n = {r['samples']}, "
                 f"KS D = {r['ks_D']:.3g}, p = {r['ks_p']:.2g}")
        ax.step(c, r["density"], where="mid", lw=1.4, label=label, color="C0" if r["drift"] else "C3")
        ref = (c, r["boltzmann"])
        print(f"{r['scene']:5s} drift={r['drift']!s:5s}: steps {r['steps']}, tau_int {r['tau_int_steps']:.1f} steps, "
              f"stride {r['stride_steps']}, samples {r['samples']}, KS D {r['ks_D']:.4g}, p {r['ks_p']:.3g}")
    # The wall's reference law checked without hydrodynamics (free draining, no drift needed).
    for r in runs:
        if scene == "wall" and r["scene"] == "wall_free_draining":
            e = np.array(r["edges"])
            c = 0.5 * (e[1:] + e[:-1])
            ax.step(c, r["density"], where="mid", lw=1.0, color="C2",
                    label=f"free draining (law check): n = {r['samples']}, KS p = {r['ks_p']:.2g}")
    if ref:
        ax.plot(ref[0], ref[1], "k--", lw=1.2, label="Boltzmann")
    if scene == "dimer":
        d = data["dimer"]
        ax.set_xlabel("centre distance r [a]")
        ax.set_title(f"Dimer a = {d['a1']:g}, {d['a2']:g}: spring k = {d['k']:g} kT/a², rest gap {d['h0']:g} a")
        ax.axvline(d["a1"] + d["a2"], color="grey", lw=0.8, ls=":")
    else:
        w = data["wall"]
        ax.set_xlabel("height z of the mobile sphere's centre [a] (z_w = %g; z_full = %g dotted)" % (w["zw"], w["z_full"]))
        ax.axvline(w["z_full"], color="grey", lw=0.8, ls=":")
        ax.set_title(f"Sphere above a {w['n']}x{w['n']} fixed layer, g = {w['g']:g} kT/a")
    ax.set_ylabel("probability density")
    ax.legend(fontsize=8)
fig.suptitle(f"Brownian SD equilibrium, full HI (git {data['machine'].get('git', '?')})", fontsize=10)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
