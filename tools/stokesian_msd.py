#!/usr/bin/env python3
"""Mean-square displacement and position-resolved diffusivity of a Stokesian trajectory.

    python3 tools/stokesian_msd.py RUN.h5 [RUN2.h5 ...] [--axis y] [--bins 0,0.4,0.8,1.2,1.6,2]
        [--fold] [--centre C] [--lags 1,2,5,10] [--blocks 5] [--json OUT.json]

For every lag tau = k frame intervals and every time origin (every frame), the displacement
dr = u(t + tau) - u(t) of each mobile particle (u the unwrapped position, docs/output.md) gives
the diffusivity estimates D_dd = dr_d^2 / (2 tau) for d = x, y, z (Einstein's relation; the
short-time self-diffusivity is its limit tau -> 0, [L24] eq. 3.2 in docs/channels.md). Each
sample is divided by that particle's Stokes-Einstein value D0 = kT / (6 pi mu a_i) (kT and mu
from the run's scene), so 1 is a free sphere. Samples are grouped by the particle's coordinate
along --axis at the time origin (--bins edges in a; --fold bins |coordinate - centre| instead,
the centre being --centre or the channel centre: the box centre in a periodic box, 0 in an open
one). Held particles (walls, fixed obstacles) are left out.

Errors: each run is cut into --blocks consecutive blocks of time origins; the standard error is
the spread of the block means over sqrt(blocks) (every run's blocks pooled), which counts the
correlation of overlapping windows and of a particle's neighbourhood within a block.

The displacements are the particles' whole motion: in an ambient flow they include advection,
so the tool refuses scenes with a [flow] unless --allow-flow is given. Runs whose particles
change (open channels' insertion and removal) are refused.
Needs numpy and h5py (Debian: python3-numpy python3-h5py).
"""
import argparse
import json
import math
import sys
import tomllib

import h5py
import numpy as np

AXES = {"x": 0, "y": 1, "z": 2}


class Refused(Exception):
    pass


def load(path, allow_flow):
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise Refused(f"{path}: cannot be read as HDF5 ({e})")
    with f:
        if "particles/all/position" not in f:
            raise Refused(f"{path}: not a Stokesian trajectory (no particles/all/position)")
        g = f["particles/all"]
        x = g["position/value"][:]
        t = g["position/time"][:]
        a = g["radius/value"][0]
        edges = g["box/edges/value"][:] if "box" in g else None
        img = g["image/value"][:] if "image" in g else None
        scene = tomllib.loads(f["parameters/stokesian/scene"][()].decode())
        git = f["parameters/stokesian/git"][()].decode() if "parameters/stokesian/git" in f else "unknown"
        if "observables/particles_present" in f:
            raise Refused(f"{path}: an open channel (particles are inserted and removed), whose particles change")
    fluid = scene.get("fluid", {})
    kT, mu = float(fluid.get("kT", 0.0)), float(fluid.get("viscosity", 1.0))
    if not kT > 0:
        raise Refused(f"{path}: [fluid] kT = {kT}: no Brownian motion, so no diffusivity")
    flow = scene.get("flow", {}).get("kind", "none")
    if flow != "none" and not allow_flow:
        raise Refused(f"{path}: [flow] kind = '{flow}': displacements include advection (--allow-flow to measure anyway)")
    if len(t) < 2:
        raise Refused(f"{path}: {len(t)} frame(s); at least 2 are needed")
    fixed = list(scene.get("particles", {}).get("fixed", []))
    n = x.shape[1]
    if len(fixed) > n:
        raise Refused(f"{path}: the scene lists {len(fixed)} particles, the trajectory {n}")
    fixed = np.array(fixed + [True] * (n - len(fixed)), dtype=bool)  # the rest: wall particles (fixed)
    if img is not None and edges is not None:
        x = x + np.einsum("fnk,fkc->fnc", img, edges)
    dom = scene.get("domain", {})
    box = np.array(dom.get("box", [0, 0, 0]), dtype=float)
    centre = 0.5 * box if dom.get("kind") == "periodic" else np.zeros(3)
    dt = np.diff(t)
    if not np.allclose(dt, dt[0], rtol=1e-6, atol=0):
        raise Refused(f"{path}: frames are not evenly spaced in time (intervals {dt.min():g} to {dt.max():g})")
    d0 = kT / (6 * math.pi * mu * a)
    return {"path": path, "u": x[:, ~fixed], "d0": d0[~fixed], "dt": float(dt[0]), "centre": centre,
            "mobile": int((~fixed).sum()), "frames": len(t), "git": git}


def analyse(runs, axis, bins, fold, centre, lags, blocks):
    dt = runs[0]["dt"]
    for r in runs:
        if not math.isclose(r["dt"], dt, rel_tol=1e-6):
            raise Refused(f"{r['path']}: frame interval {r['dt']:g}, others {dt:g}")
    out = []
    nb = len(bins) - 1
    for k in lags:
        tau = k * dt
        # Per bin and block: sums of D_xx, D_yy, D_zz (over D0) and the sample count.
        acc = []
        for r in runs:
            u = r["u"]
            nf = u.shape[0]
            if nf <= k:
                raise Refused(f"{r['path']}: {nf} frames, too few for a lag of {k}")
            dr = u[k:] - u[:-k]
            q = u[:-k, :, axis] - (r["centre"][axis] if centre is None else centre)
            if fold:
                q = np.abs(q)
            b = np.digitize(q, bins) - 1  # -1 or nb: outside every bin
            blk = np.broadcast_to(((np.arange(nf - k) * blocks) // (nf - k))[:, None], b.shape)
            est = dr ** 2 / (2 * tau) / r["d0"][None, :, None]
            inside = (b >= 0) & (b < nb)
            cell = (b * blocks + blk)[inside]  # one (bin, block) cell per sample
            s = np.stack([np.bincount(cell, weights=est[..., d][inside], minlength=nb * blocks) for d in range(3)]
                         + [np.bincount(cell, minlength=nb * blocks).astype(float)], axis=-1)
            acc.append(s.reshape(nb, blocks, 4))
        acc = np.concatenate(acc, axis=1)  # (bins, blocks of every run, 4)
        for i in range(nb):
            c = acc[i, :, 3]
            row = {"lag_frames": k, "tau": tau, "bin": [None if math.isinf(v) else v for v in (bins[i], bins[i + 1])], "samples": int(c.sum())}
            if c.sum() == 0:
                out.append(row)
                continue
            mean = acc[i, :, :3].sum(axis=0) / c.sum()
            full = c > 0
            bm = acc[i, full, :3] / c[full, None]
            se = bm.std(axis=0, ddof=1) / math.sqrt(full.sum()) if full.sum() > 1 else np.full(3, math.nan)
            row.update({"D": mean.tolist(), "se": se.tolist(), "blocks": int(full.sum())})
            # The axis' component against the mean of the other two (normal against parallel in a slit).
            other = [d for d in range(3) if d != axis]
            par = 0.5 * (bm[:, other[0]] + bm[:, other[1]])
            diff = bm[:, axis] - par
            row["D_axis"] = float(mean[axis])
            row["D_other"] = float(0.5 * (mean[other[0]] + mean[other[1]]))
            row["axis_minus_other"] = float(row["D_axis"] - row["D_other"])
            row["se_axis_minus_other"] = float(diff.std(ddof=1) / math.sqrt(full.sum())) if full.sum() > 1 else math.nan
            out.append(row)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("trajectory", nargs="+")
    p.add_argument("--axis", choices=sorted(AXES), default="y", help="coordinate the bins are along (default y)")
    p.add_argument("--bins", default=None, help="bin edges in a, comma-separated (default: one bin for all)")
    p.add_argument("--fold", action="store_true", help="bin |coordinate - centre| (the two halves of a channel together)")
    p.add_argument("--centre", type=float, default=None, help="centre for --fold and the bins [a] (default: the channel centre)")
    p.add_argument("--lags", default="1,2,5,10", help="lags in frame intervals, comma-separated (default 1,2,5,10)")
    p.add_argument("--blocks", type=int, default=5, help="time blocks per run for the standard errors (default 5, >= 2)")
    p.add_argument("--allow-flow", action="store_true", help="measure runs with an ambient flow (advection included)")
    p.add_argument("--json", default=None, help="also write the table as JSON")
    a = p.parse_args(argv)
    try:
        try:
            lags = [int(v) for v in a.lags.split(",")]
        except ValueError:
            raise Refused(f"--lags {a.lags!r}: comma-separated whole numbers of frame intervals expected")
        if not lags or min(lags) < 1:
            raise Refused(f"--lags {a.lags!r}: every lag must be at least 1 frame interval")
        if a.blocks < 2:
            raise Refused(f"--blocks {a.blocks}: at least 2 blocks are needed for a standard error")
        if a.bins is None:
            bins = [-math.inf, math.inf]
        else:
            try:
                bins = [float(v) for v in a.bins.split(",")]
            except ValueError:
                raise Refused(f"--bins {a.bins!r}: comma-separated numbers (bin edges in a) expected")
            if len(bins) < 2 or any(b1 <= b0 for b0, b1 in zip(bins, bins[1:])):
                raise Refused(f"--bins {a.bins!r}: at least two increasing edges expected")
        runs = [load(path, a.allow_flow) for path in a.trajectory]
        rows = analyse(runs, AXES[a.axis], bins, a.fold, a.centre, lags, a.blocks)
    except Refused as e:
        sys.stderr.write(f"stokesian_msd: {e}\n")
        return 2
    ax = a.axis
    print(f"{len(runs)} run(s), {sum(r['frames'] for r in runs)} frames, {runs[0]['mobile']} mobile particles, "
          f"frame interval {runs[0]['dt']:g}; D / D0 with standard errors")
    print(f"{'lag':>5} {'tau':>8} {'bin [a]':>13} {'samples':>8} {'D_x':>14} {'D_y':>14} {'D_z':>14}"
          f" {'D_' + ax + ' - others':>18}")
    for r in rows:
        lo, hi = r["bin"]
        name = "all" if lo is None and hi is None else f"{lo if lo is not None else '-inf'}-{hi if hi is not None else 'inf'}"
        if "D" not in r:
            print(f"{r['lag_frames']:>5} {r['tau']:>8.4g} {name:>13} {0:>8}")
            continue
        cells = " ".join(f"{d:7.4f} ({s:.4f})" for d, s in zip(r["D"], r["se"]))
        print(f"{r['lag_frames']:>5} {r['tau']:>8.4g} {name:>13} {r['samples']:>8} {cells}"
              f" {r['axis_minus_other']:+8.4f} ({r['se_axis_minus_other']:.4f})")
    if a.json:
        meta = {"trajectories": a.trajectory, "axis": ax, "fold": a.fold, "blocks": a.blocks,
                "mobile": runs[0]["mobile"], "frame_interval": runs[0]["dt"],
                "git": " ".join(sorted({r["git"] for r in runs}))}  # the build(s) that wrote the runs
        with open(a.json, "w") as f:
            json.dump({"meta": meta, "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
