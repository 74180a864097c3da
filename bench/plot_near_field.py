#!/usr/bin/python3
"""Chart the near-field benchmark: assembly and CHOLMOD factorisation time against N for each
volume fraction (with fitted exponents), and the fill nnz(L)/nnz(R).

usage: plot_near_field.py [RESULTS.json] [OUT.png]   (default: bench/results/near_field.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/near_field.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
fig, axes = plt.subplots(2, 3, figsize=(14, 8))
for r_i, dof in enumerate((6, 11)):
    level = "FT" if dof == 6 else "FTS"
    phis = sorted({r["params"]["phi"] for r in rows if r["params"]["dof"] == dof})
    for phi in phis:
        pts = sorted((r["params"]["N"], r["phases"]["assembly"], r["phases"]["refactor"],
                      r["params"]["nnz_L"] / r["params"]["nnz_R"]) for r in rows
                     if r["params"]["dof"] == dof and r["params"]["phi"] == phi)
        if not pts:
            continue
        n, ta, tf, fill = np.array(pts).T
        sa = np.polyfit(np.log(n), np.log(ta), 1)[0] if len(n) > 1 else float("nan")
        sf = np.polyfit(np.log(n), np.log(tf), 1)[0] if len(n) > 1 else float("nan")
        axes[r_i, 0].loglog(n, ta, "-o", label=f"phi={phi:.1f} (slope {sa:.2f})")
        axes[r_i, 1].loglog(n, tf, "-o", label=f"phi={phi:.1f} (slope {sf:.2f})")
        axes[r_i, 2].semilogx(n, fill, "-o", label=f"phi={phi:.1f}")
        print(f"{level} phi={phi:.1f}: assembly exponent {sa:.2f}, factorisation exponent {sf:.2f}, fill {fill[-1]:.2f} at N={int(n[-1])}")
    axes[r_i, 0].set_title(f"{level}: near-field assembly")
    axes[r_i, 1].set_title(f"{level}: CHOLMOD numeric factorisation")
    axes[r_i, 2].set_title(f"{level}: fill nnz(L)/nnz(R)")
    for ax in axes[r_i]:
        ax.set_xlabel("N particles")
        ax.legend(fontsize=7)
    axes[r_i, 0].set_ylabel("time [s]")
    axes[r_i, 1].set_ylabel("time [s]")
m = data["machine"]
fig.suptitle(f"{m.get('cpu', '?')}, {m.get('compiler', '?')}, {m.get('git', '?')}, {m.get('date', '?')}", fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
