#!/usr/bin/env python3
"""Chart a cluster file written by `stokesian clusters` (docs/clusters.md).

    python3 tools/stokesian_clusters_plot.py RUN.clusters.h5 [--out RUN.clusters.png]

Panels against time: (a) the number of clusters over the number of particles N_c/N; (b) the
number of singlets, doublets, triplets, quadruplets and larger clusters; (c) the largest cluster
and the number- and weight-average sizes; (d) the ensemble fractal dimension D_f (where defined)
and the clusters in its fit; (e) radius of gyration against size of every cluster of the last
frame with the fitted n = k_f (R_g/a)^D_f. Needs numpy, matplotlib and h5py (Debian:
python3-numpy python3-matplotlib python3-h5py).
"""
import argparse
import os
import sys

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("clusters")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    out = a.out or os.path.splitext(a.clusters)[0] + ".png"
    with h5py.File(a.clusters, "r") as f:
        if "frames" not in f or "size_histogram" not in f:
            sys.stderr.write(f"{a.clusters}: not a file of `stokesian clusters`\n")
            return 1
        fr = {k: f["frames/" + k][:] for k in f["frames"]}
        hist = f["size_histogram"][:]
        cl = {k: f["clusters/" + k][:] for k in f["clusters"]}
        gap = f.attrs.get("bond_gap", b"?")
    gap = gap.decode() if isinstance(gap, bytes) else str(gap)
    t, n = fr["time"], fr["particles"]
    fig, ax = plt.subplots(1, 5, figsize=(21, 4.2))
    ax[0].plot(t, fr["clusters"] / n, "k-")
    ax[0].set_ylabel(r"$N_c / N$")
    ax[0].set_title("(a) clusters per particle", fontsize=10)
    names = ["singlets", "doublets", "triplets", "quadruplets"]
    for s in range(min(4, hist.shape[1])):
        ax[1].plot(t, hist[:, s], label=names[s])
    if hist.shape[1] > 4:
        ax[1].plot(t, hist[:, 4:].sum(axis=1), label="5 and more")
    ax[1].set_ylabel("number of clusters")
    ax[1].set_title("(b) clusters by size", fontsize=10)
    ax[1].legend(fontsize=8)
    ax[2].plot(t, fr["largest"], label="largest")
    ax[2].plot(t, fr["mean_size"], label="number-average")
    ax[2].plot(t, fr["weight_mean_size"], label="weight-average")
    ax[2].set_ylabel("cluster size")
    ax[2].set_title("(c) cluster sizes", fontsize=10)
    ax[2].legend(fontsize=8)
    ax[3].plot(t, fr["fractal_dimension"], "o-", ms=3, label=r"$D_f$")
    ax3 = ax[3].twinx()
    ax3.plot(t, fr["fractal_clusters"], "C1:", label="clusters in the fit")
    ax3.set_ylabel("clusters in the fit", color="C1")
    ax[3].set_ylabel(r"fractal dimension $D_f$")
    ax[3].set_title("(d) ensemble fractal dimension", fontsize=10)
    last = cl["frame"] == cl["frame"].max()
    ax[4].loglog(cl["radius_of_gyration"][last], cl["size"][last], "o", ms=4)
    df, kf, am = fr["fractal_dimension"][-1], fr["fractal_prefactor"][-1], fr["mean_radius"][-1]
    if np.isfinite(df):
        rg = np.geomspace(np.nanmin(cl["radius_of_gyration"][last]), np.nanmax(cl["radius_of_gyration"][last]), 20)
        ax[4].loglog(rg, kf * (rg / am) ** df, "k--", label=rf"$D_f$ = {df:.2f}")
        ax[4].legend(fontsize=8)
    ax[4].set_xlabel(r"radius of gyration $R_g$ [a]")
    ax[4].set_ylabel("cluster size n")
    ax[4].set_title(f"(e) last frame (t = {t[-1]:.3g})", fontsize=10)
    for x in ax[:4]:
        x.set_xlabel("time")
    for x in ax:
        x.grid(alpha=0.3)
    fig.suptitle(f"{os.path.basename(a.clusters)}: N = {int(n[0])}, bonds: gap <= {gap} a", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
