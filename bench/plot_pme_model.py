#!/usr/bin/env python3
"""Chart of bench_pme_model (bench/results/pme_model.json): the PME cost model's cost per particle
against N for the engine's fixed 256 MB real-space scalar cache and for budgets growing with N
(top row), and the real-space memory per particle each choice implies (bottom row). F and FTS,
phi 0.1 and 0.4, tolerances 1e-3, 1e-4, 1e-6. Prints the modelled exponents over the N range.

    python3 bench/plot_pme_model.py [bench/results/pme_model.json] [bench/results/pme_model.png]
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

BUDGETS = {0: ("256 MB (engine)", "-"), 1: ("8 kB / particle", "--"), 2: ("unbounded", ":")}
TOLS = {1e-3: "C0", 1e-4: "C1", 1e-6: "C2"}


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "bench/results/pme_model.json"
    out = sys.argv[2] if len(sys.argv) > 2 else "bench/results/pme_model.png"
    rows = json.load(open(path))["rows"]
    fig, axes = plt.subplots(2, 4, figsize=(16, 7.5), sharex=True)
    for col, (mom, phi) in enumerate([(3, 0.1), (3, 0.4), (11, 0.1), (11, 0.4)]):
        name = "F" if mom == 3 else "FTS"
        for tol, colour in TOLS.items():
            for b, (label, style) in BUDGETS.items():
                sel = sorted((r for r in rows if r["params"]["moments"] == mom and r["params"]["phi"] == phi
                              and abs(r["params"]["tol"] / tol - 1) < 1e-9 and r["params"]["budget"] == b),
                             key=lambda r: r["params"]["N"])
                if not sel:
                    continue
                n = np.array([r["params"]["N"] for r in sel])
                us = np.array([r["phases"]["cost_per_particle_us"] for r in sel])
                kb = np.array([r["params"]["real_bytes_per_particle"] for r in sel]) / 1024
                slope = np.polyfit(np.log(n), np.log(us * n), 1)[0] if len(n) > 1 else float("nan")
                print("%-3s phi %.1f tol %.0e budget %-16s exponent %.3f  us/particle %s  kB/particle %s" % (
                    name, phi, tol, label, slope, " ".join("%.2f" % v for v in us), " ".join("%.1f" % v for v in kb)))
                axes[0, col].plot(n, us, style, color=colour, marker="o", ms=3,
                                  label="tol %.0e, %s" % (tol, label) if col == 0 else None)
                axes[1, col].plot(n, kb, style, color=colour, marker="o", ms=3)
        axes[0, col].set_title("%s, phi = %.1f" % (name, phi))
        axes[1, col].set_xlabel("N")
        for r in range(2):
            axes[r, col].set_xscale("log")
    axes[0, 0].set_ylabel("modelled cost per particle [us], one thread")
    axes[1, 0].set_ylabel("real-space memory per particle [kB]\n(pair data twice + scalar cache when kept)")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("PME cost model: the fixed scalar-cache budget makes the cost per particle jump from N ~ 1e5;"
                 " a budget growing with N keeps it flat at several times the memory")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
