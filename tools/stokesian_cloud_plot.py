#!/usr/bin/env python3
"""Pictures of a settling cloud (docs/clouds.md): snapshots and the cloud observables of a run.

    python3 tools/stokesian_cloud_plot.py RUN.h5 [--out RUN_cloud.png] [--snapshots 6]

Top row: side views (x horizontal, z vertical) of every sphere within 3 R0 of the cloud's centroid
(`cloud_centroid`) at evenly spaced frames, centred on it. Second row: the same frames cut through
the centroid, the slab
|y - c_y| < R0/4 (R0 the first frame's `cloud_radius`): a torus shows as two lobes. Third row: the
same frames from above (x, y), without the tail above the cloud (z - c_z > R0): the ring of a
torus, and the lobes into which it breaks up. Bottom row:
`cloud_axis_fraction` (0.092 for a uniform sphere, dotted), the lost fraction `cloud_lost`/N,
`cloud_parts`, and the eigenvalues of `cloud_gyration` over R0^2/5, against the distance fallen in
initial cloud radii. Needs numpy, matplotlib and h5py (Debian: python3-numpy python3-matplotlib
python3-h5py). Exit status: 0 written, 1 usage or a trajectory without cloud observables.
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
    ap.add_argument("trajectory")
    ap.add_argument("--out", default=None)
    ap.add_argument("--snapshots", type=int, default=6)
    a = ap.parse_args()
    out = a.out or os.path.splitext(a.trajectory)[0] + "_cloud.png"
    with h5py.File(a.trajectory, "r") as f:
        if "observables/cloud_radius" not in f:
            sys.stderr.write(f"{a.trajectory}: no cloud observables (run with [output] cloud = true)\n")
            return 1
        x = f["particles/all/position/value"]
        t = f["particles/all/position/time"][:]
        ob = {k: (f[f"observables/{k}/time"][:], f[f"observables/{k}/value"][:])
              for k in ("cloud_centroid", "cloud_radius", "cloud_axis_fraction", "cloud_lost", "cloud_parts",
                        "cloud_gyration", "cloud_particles")}
        n = x.shape[1]
        R0 = ob["cloud_radius"][1][0]
        c0 = ob["cloud_centroid"][1][0]
        frames = np.unique(np.linspace(0, len(t) - 1, a.snapshots).round().astype(int))
        fig = plt.figure(figsize=(3.0 * len(frames), 12.6))
        gs = fig.add_gridspec(4, len(frames), height_ratios=[1.15, 1.15, 1.15, 1.0])
        link_groups = None
        for col, k in enumerate(frames):
            p = x[k]
            ck = ob["cloud_centroid"][1][np.searchsorted(ob["cloud_centroid"][0], t[k])]
            d = p - ck
            r = np.linalg.norm(d, axis=1)
            far = r > 3.0 * R0
            fall = (c0[2] - ck[2]) / R0
            for row, sel in ((0, np.ones(n, bool)), (1, np.abs(d[:, 1]) < 0.25 * R0)):
                ax = fig.add_subplot(gs[row, col])
                ax.scatter(d[sel & ~far, 0] / R0, d[sel & ~far, 2] / R0, s=1.0, c="C0", lw=0)
                ax.set_xlim(-2.5, 2.5)
                ax.set_ylim(-3.0, 2.0)
                ax.set_aspect("equal")
                ax.tick_params(labelsize=7)
                if row == 0:
                    ax.set_title(f"t = {t[k]:.3g}, fallen {fall:.0f} $R_0$", fontsize=9)
                if col == 0:
                    ax.set_ylabel(("all spheres" if row == 0 else r"slab $|y - c_y| < R_0/4$") + "\n$(z - c_z)/R_0$",
                                  fontsize=8)
                ax.set_xlabel(r"$(x - c_x)/R_0$", fontsize=8)
            ax = fig.add_subplot(gs[2, col])
            sel = ~far & (d[:, 2] < R0)
            ax.scatter(d[sel, 0] / R0, d[sel, 1] / R0, s=1.0, c="C0", lw=0)
            ax.set_xlim(-2.5, 2.5)
            ax.set_ylim(-2.5, 2.5)
            ax.set_aspect("equal")
            ax.tick_params(labelsize=7)
            if col == 0:
                ax.set_ylabel("from above\n$(y - c_y)/R_0$", fontsize=8)
            ax.set_xlabel(r"$(x - c_x)/R_0$", fontsize=8)
        tc, cz = ob["cloud_centroid"][0], ob["cloud_centroid"][1][:, 2]
        fallen = (c0[2] - cz) / R0

        def at(name):
            tt, v = ob[name]
            return np.interp(tt, tc, fallen), v

        ncols = len(frames)
        span = max(1, ncols // 4)
        axes = [fig.add_subplot(gs[3, i * span:(i + 1) * span if i < 3 else ncols]) for i in range(4)]
        xs, v = at("cloud_axis_fraction")
        axes[0].plot(xs, v, "C0-")
        axes[0].axhline(1 - (15 / 16) ** 1.5, color="k", ls=":", lw=0.8)
        axes[0].set_ylabel("cloud_axis_fraction", fontsize=8)
        xs, v = at("cloud_lost")
        axes[1].plot(xs, v / n, "C1-")
        axes[1].set_ylabel("lost / N", fontsize=8)
        xs, v = at("cloud_parts")
        axes[2].step(xs, v, "C2-", where="post")
        axes[2].set_ylabel("cloud_parts", fontsize=8)
        xs, v = at("cloud_gyration")
        for j in range(3):
            axes[3].plot(xs, v[:, j] / (R0 * R0 / 5.0), f"C{3 + j}-", label=f"eigenvalue {j + 1}")
        axes[3].set_ylabel(r"gyration / ($R_0^2/5$)", fontsize=8)
        axes[3].legend(fontsize=7)
        for ax in axes:
            ax.set_xlabel("distance fallen / $R_0$", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        fig.suptitle(f"{os.path.basename(a.trajectory)}: N = {n}, $R_0$ = {R0:.3g} a", fontsize=10)
        fig.tight_layout()
        fig.savefig(out, dpi=100)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
