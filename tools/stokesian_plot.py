#!/usr/bin/env python3
"""Charts of one Stokesian trajectory (H5MD, docs/output.md) in one PNG.

    stokesian plot RUN.h5 [--out RUN.png] [--frame -1] [--projection xy]
    python3 tools/stokesian_plot.py RUN.h5 [same options]

Panels: every scalar observable against time (/observables/<name>); the radius histogram; the
distribution of surface gaps h = |r_ij| - a_i - a_j below 2 a in the snapshot frame (minimum image
in periodic boxes; all pairs, skipped above 4000 particles); the speed distribution |U| when
velocities are recorded; a snapshot: the particles projected onto a plane as circles of their
radius, coloured by the third coordinate, with the periodic cell outlined.
Needs numpy, matplotlib and h5py (Debian: python3-numpy python3-matplotlib python3-h5py).
Exit status: 0 written, 1 usage, 4 unreadable trajectory or image not written.
"""
import argparse
import os
import sys

try:
    import numpy as np
    import h5py
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Polygon
except ImportError as e:  # pragma: no cover - environment problem
    sys.stderr.write(
        f"stokesian_plot.py: {e}; needs numpy, matplotlib and h5py "
        "(Debian: python3-numpy python3-matplotlib python3-h5py), run with a python3 that has them "
        "(stokesian plot --python PATH)\n"
    )
    sys.exit(4)

MAX_PAIRS_N = 4000  # gap distribution over all pairs up to this many particles
AXES = {"xy": (0, 1, 2), "xz": (0, 2, 1), "yz": (1, 2, 0)}
NAMES = "xyz"


def text(v):
    v = v[()]
    return v.decode() if isinstance(v, bytes) else str(v)


def lattice(f, frame, n_frames):
    """Lattice matrix (rows a, b, c) of the snapshot frame, or None for an open domain."""
    box = f["particles/all/box"]
    boundary = [b.decode() if isinstance(b, bytes) else str(b) for b in box.attrs["boundary"]]
    if "periodic" not in boundary or "edges" not in box:
        return None
    edges = box["edges"]
    if isinstance(edges, h5py.Group):  # Lees-Edwards: time-dependent edge vectors
        v = edges["value"]
        return np.asarray(v[min(frame, v.shape[0] - 1)], dtype=float)
    return np.diag(np.asarray(edges[()], dtype=float))


def gaps(x, a, A):
    """Surface gaps below 2 a over all pairs (minimum image with lattice A)."""
    n = len(x)
    out = []
    Ainv = np.linalg.inv(A) if A is not None else None
    for i in range(n - 1):
        d = x[i] - x[i + 1 :]
        if A is not None:
            s = d @ Ainv
            s -= np.round(s)
            d = s @ A
        h = np.linalg.norm(d, axis=1) - a[i] - a[i + 1 :]
        out.append(h[h < 2.0])
    return np.concatenate(out) if out else np.empty(0)


def main():
    p = argparse.ArgumentParser(description="Charts of a Stokesian trajectory in one PNG.")
    p.add_argument("trajectory")
    p.add_argument("--out", help="image file (default: the trajectory's name with .png)")
    p.add_argument("--frame", type=int, default=-1, help="snapshot frame; negative counts from the end")
    p.add_argument("--projection", choices=sorted(AXES), default="xy", help="plane of the snapshot")
    args = p.parse_args()
    out = args.out or os.path.splitext(args.trajectory)[0] + ".png"

    try:
        f = h5py.File(args.trajectory, "r")
    except OSError as e:
        sys.stderr.write(f"stokesian_plot.py: cannot read {args.trajectory}: {e}\n")
        return 4
    with f:
        if "particles/all/position/value" not in f:
            sys.stderr.write(f"stokesian_plot.py: {args.trajectory}: no /particles/all/position (not a Stokesian trajectory)\n")
            return 4
        pos = f["particles/all/position/value"]
        n_frames, n = pos.shape[0], pos.shape[1]
        if n_frames == 0:
            sys.stderr.write(f"stokesian_plot.py: {args.trajectory}: no frames\n")
            return 4
        frame = args.frame if args.frame >= 0 else n_frames + args.frame
        if not 0 <= frame < n_frames:
            sys.stderr.write(f"stokesian_plot.py: --frame {args.frame}: the file has {n_frames} frames (0 to {n_frames - 1}, or -1 to -{n_frames})\n")
            return 1
        x = np.asarray(pos[frame], dtype=float)
        t_frame = float(f["particles/all/position/time"][frame])
        step_frame = int(f["particles/all/position/step"][frame])
        a = np.asarray(f["particles/all/radius/value"][frame], dtype=float) if "particles/all/radius" in f else np.ones(n)
        u = np.asarray(f["particles/all/velocity/value"][frame], dtype=float) if "particles/all/velocity" in f else None
        A = lattice(f, frame, n_frames)
        # Open channels keep a slot per possible particle; an empty slot (id -1) holds NaN.
        slots = n
        present = np.all(np.isfinite(x), axis=1)
        if "particles/all/id" in f:
            present &= np.asarray(f["particles/all/id/value"][frame]) >= 0
        if not present.all():
            x, a = x[present], a[present]
            u = u[present] if u is not None else None
            n = int(present.sum())
            if n == 0:
                sys.stderr.write(f"stokesian_plot.py: {args.trajectory}: frame {frame} has no particle (all {slots} slots empty)\n")
                return 4
        obs = {}
        if "observables" in f:
            def visit(name, obj):
                if isinstance(obj, h5py.Group) and "value" in obj and "time" in obj:
                    v = obj["value"]
                    if v.ndim == 1 and v.shape[0] > 0:
                        obs[name] = (np.asarray(obj["time"][()], dtype=float), np.asarray(v[()], dtype=float))
            f["observables"].visititems(visit)
        model = text(f["parameters/stokesian/model_key"]) if "parameters/stokesian/model_key" in f else ""

    plt.rcParams.update({"font.size": 9})
    fig = plt.figure(figsize=(16, 9), dpi=100)
    outer = fig.add_gridspec(1, 3, width_ratios=[1.0, 1.0, 1.45], wspace=0.28, left=0.05, right=0.95, top=0.9, bottom=0.07)
    fig.suptitle(
        f"{os.path.basename(args.trajectory)}: {n} particles" + (f" (of {slots} slots)" if slots != n else "") +
        f", {n_frames} frames, snapshot frame {frame} "
        f"(step {step_frame}, t = {t_frame:.4g})\n{model}",
        fontsize=11,
    )

    # Observables against time.
    names = sorted(obs)
    if names:
        g = outer[0].subgridspec(len(names), 1, hspace=0.12)
        first = None
        for k, name in enumerate(names):
            ax = fig.add_subplot(g[k], sharex=first)
            first = first or ax
            t, v = obs[name]
            ax.plot(t, v, ".-" if len(t) < 60 else "-", lw=1.2, ms=3)
            ax.text(0.01, 0.93, name, transform=ax.transAxes, ha="left", va="top", fontsize=9,
                    bbox=dict(facecolor="white", edgecolor="0.7", alpha=0.85, pad=2))
            ax.grid(alpha=0.3)
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
            if k < len(names) - 1:
                ax.tick_params(labelbottom=False)
        ax.set_xlabel("time")
        first.set_title("observables")
    else:
        ax = fig.add_subplot(outer[0])
        ax.text(0.5, 0.5, "no scalar observables", ha="center", va="center")
        ax.set_axis_off()

    # Particle statistics of the snapshot frame.
    g = outer[1].subgridspec(3, 1, hspace=0.45)
    ax = fig.add_subplot(g[0])
    if np.ptp(a) > 1e-12 * a.max():
        ax.hist(a, bins=min(40, max(5, n // 5)), color="tab:blue", alpha=0.8)
        ax.set_title(f"radius ({a.min():.3g} to {a.max():.3g} a)")
        ax.set_xlabel("a")
        ax.set_ylabel("particles")
    else:
        ax.text(0.5, 0.5, f"all {n} particles have radius {a[0]:.4g} a", ha="center", va="center", transform=ax.transAxes,
                fontsize=11)
        ax.set_title("radius")
        ax.set_axis_off()

    ax = fig.add_subplot(g[1])
    if n < 2:
        ax.text(0.5, 0.5, "one particle: no gaps", ha="center", va="center", transform=ax.transAxes)
    elif n > MAX_PAIRS_N:
        ax.text(0.5, 0.5, f"gap distribution skipped ({n} > {MAX_PAIRS_N} particles)", ha="center", va="center", transform=ax.transAxes)
    else:
        h = gaps(x, a, A)
        if h.size:
            ax.hist(h, bins=50, color="tab:orange", alpha=0.85)
            ax.axvline(0.0, color="k", lw=0.8)
            ax.set_title(f"gaps < 2 a: {h.size} pairs, smallest {h.min():.3g} a, {int((h < 0).sum())} overlapping")
        else:
            ax.text(0.5, 0.5, "no pair closer than 2 a", ha="center", va="center", transform=ax.transAxes)
            ax.set_title("surface gaps")
    ax.set_xlabel("gap h [a]")
    ax.set_ylabel("pairs")

    ax = fig.add_subplot(g[2])
    if u is not None:
        speed = np.linalg.norm(u, axis=1)
        ax.hist(speed, bins=min(50, max(5, n // 4)), color="tab:green", alpha=0.85)
        ax.set_title(f"speed |U| (mean {speed.mean():.3g}, max {speed.max():.3g})")
        ax.set_xlabel("|U| [a / time]")
        ax.set_ylabel("particles")
    else:
        ax.text(0.5, 0.5, "velocity not recorded", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()

    # Snapshot.
    i, j, k = AXES[args.projection]
    ax = fig.add_subplot(outer[2])
    depth = x[:, k]
    circles = PatchCollection([Circle((x[m, i], x[m, j]), a[m]) for m in range(n)], cmap="viridis", alpha=0.75,
                              edgecolor="k", linewidth=0.4)
    circles.set_array(depth)
    ax.add_collection(circles)
    cb = fig.colorbar(circles, ax=ax, fraction=0.04, pad=0.02)
    cb.set_label(f"{NAMES[k]} [a]")
    lo = (x[:, [i, j]] - a[:, None]).min(axis=0)
    hi = (x[:, [i, j]] + a[:, None]).max(axis=0)
    if A is not None:
        # The cell projected onto the plane: the parallelogram of the two lattice vectors in it.
        e1, e2 = A[i][[i, j]], A[j][[i, j]]
        corners = np.array([[0, 0], e1, e1 + e2, e2])
        ax.add_patch(Polygon(corners, closed=True, fill=False, edgecolor="tab:red", lw=1.5, ls="--", label="periodic cell"))
        ax.legend(loc="upper right")
        lo = np.minimum(lo, corners.min(axis=0))
        hi = np.maximum(hi, corners.max(axis=0))
    pad = 0.03 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{NAMES[i]} [a]")
    ax.set_ylabel(f"{NAMES[j]} [a]")
    ax.set_title(f"snapshot, {args.projection} projection")

    try:
        fig.savefig(out)
    except OSError as e:
        sys.stderr.write(f"stokesian_plot.py: cannot write {out}: {e}\n")
        return 4
    return 0


if __name__ == "__main__":
    try:
        status = main()
    except Exception as e:  # an unreadable or unexpected file: exit 4 with the reason (1 is kept for usage)
        sys.stderr.write(f"stokesian_plot.py: {type(e).__name__}: {e}\n")
        status = 4
    sys.exit(status)
