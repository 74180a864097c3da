#!/usr/bin/python3
"""Extract the time series of fouling runs (configs/t_junction.toml, configs/contraction.toml run
long; issue 17, docs/channels.md "Fouling runs") from their H5MD trajectories into one JSON file
that bench/plot_fouling.py charts: per frame the time, pressure_drop_particles, the areal fraction
of each section and of the whole channel, the particles present, inserted and removed, and the
deposited particles (interior spheres within `contact` a of a wall particle, surface to surface).
A run still going (or killed) is read as far as its visible frames go.

usage: fouling_summary.py NAME=RUN.h5 [NAME=RUN.h5 ...] [--out bench/results/fouling.json] [--note TEXT]
"""
import json
import os
import platform
import subprocess
import sys

import h5py
import numpy as np

CONTACT = 0.05  # [a] surface gap below which an interior sphere counts as deposited on a wall


def deposited(x, r, ids, fixed_from):
    """Interior spheres within CONTACT of a wall particle (slots >= fixed_from are walls)."""
    present = np.where(ids[:fixed_from] >= 0)[0]
    if len(present) == 0:
        return 0
    walls = x[fixed_from:, :2]
    rw = r[fixed_from:]
    count = 0
    for i in present:
        d = np.linalg.norm(walls - x[i, :2], axis=1) - rw - r[i]
        count += bool(np.min(d) < CONTACT)
    return count


def branches(outline, openings, inlet):
    """The outline's branches as engine/core/outline.hpp defines them (OutlineBranches), for files
    written before pressure_drop_branches existed: openings with the same flow direction and
    overlapping spans across it form one branch (the inlet's first); a point belongs to the first
    branch whose strip holds it and from which it reaches one of the branch's openings along the
    flow without entering another branch's strip."""
    v = np.array(outline, float)
    n = len(v)
    a2 = sum(v[k, 0] * v[(k + 1) % n, 1] - v[(k + 1) % n, 0] * v[k, 1] for k in range(n))
    orient = 1.0 if a2 > 0 else -1.0
    eps = 1e-9 * (1.0 + np.abs(v).max())

    def outward(k):
        t = v[(k + 1) % n] - v[k]
        t = t / np.linalg.norm(t)
        return orient * np.array([t[1], -t[0]])

    def across(d, p):
        return -d[1] * p[0] + d[0] * p[1]

    out = []
    for k in [inlet] + [e for e in sorted(openings) if e != inlet]:
        d = -outward(k) if k == inlet else outward(k)
        s0, s1 = across(d, v[k]), across(d, v[(k + 1) % n])
        lo, hi = min(s0, s1), max(s0, s1)
        at = d @ (0.5 * (v[k] + v[(k + 1) % n]))
        for b in out:
            if b["d"] @ d > 1 - 1e-9 and lo <= b["hi"] + eps and hi >= b["lo"] - eps:
                b["lo"], b["hi"] = min(b["lo"], lo), max(b["hi"], hi)
                b["openings"].append(k)
                b["at"].append(at)
                break
        else:
            out.append({"d": d, "lo": lo, "hi": hi, "width": float(np.linalg.norm(v[(k + 1) % n] - v[k])),
                        "openings": [k], "at": [at]})

    def of_point(p, e=0.0):
        for i, b in enumerate(out):
            if not b["lo"] - e <= across(b["d"], p) <= b["hi"] + e:
                continue
            for at in b["at"]:
                T = at - b["d"] @ p
                t0, t1 = min(0.0, T), max(0.0, T)
                blocked = False
                for j, c in enumerate(out):
                    g0 = across(c["d"], p)
                    if j == i or c["lo"] - e <= g0 <= c["hi"] + e:
                        continue
                    g1 = across(c["d"], b["d"])
                    if abs(g1) < 1e-12:
                        continue
                    ta, tb = sorted(((c["lo"] - g0) / g1, (c["hi"] - g0) / g1))
                    if min(tb, t1) - max(ta, t0) > eps:
                        blocked = True
                        break
                if not blocked:
                    return i
        return -1

    return out, of_point, eps, orient


def branch_series(scene, obs, x, r, ids, capacity, steps):
    """pressure_drop_branches and areal_fraction_branches: read, or rebuilt from the per-edge wall
    stresses (each wall edge's (section) sums of -F.t and F.n_in give -F.d for its branch exactly
    when all its wall particles belong to one branch, as in the T-junction and the contraction)."""
    if "pressure_drop_branches" in obs:
        return (obs["pressure_drop_branches/value"][:].tolist(), obs["areal_fraction_branches/value"][:].tolist(),
                "recorded")
    import tomllib
    w = tomllib.loads(scene)["walls"]
    outline, openings, inlet = w["outline"], w["openings"], w["inlet"]
    depth, ns = w.get("depth", 2.0 * w.get("radius", 1.0)), w.get("sections", 1)
    br, of_point, eps, orient = branches(outline, openings, inlet)
    v = np.array(outline, float)
    n = len(v)
    wall_edges = [k for k in range(n) if k not in openings]
    shear = obs["wall_shear_stress/value"][:]   # [frames, walls, sections]
    normal = obs["wall_normal_stress/value"][:]
    dp = np.zeros((shear.shape[0], len(br)))
    for w_i, k in enumerate(wall_edges):
        A, B = v[k], v[(k + 1) % n]
        length = np.linalg.norm(B - A)
        t = (B - A) / length
        n_in = -orient * np.array([t[1], -t[0]])
        owners = {of_point(A + (j + 0.5) / ns * (B - A), eps) for j in range(ns)}
        if len(owners) != 1:
            raise SystemExit(f"wall edge {k} spans several branches: rebuild needs pressure_drop_branches in the file")
        b = owners.pop()
        if b < 0:
            continue
        d = br[b]["d"]
        area = length / ns * depth
        # -F.d = (d.t)(-F.t) - (d.n_in)(F.n_in), summed over the edge's sections.
        dp[:, b] += area * ((d @ t) * shear[:, w_i, :].sum(axis=1) - (d @ n_in) * normal[:, w_i, :].sum(axis=1))
    for b in range(len(br)):
        dp[:, b] /= br[b]["width"] * depth
    # Areal fractions: the areas each branch owns, by cell-centre sampling at (narrowest opening)/50.
    h = min(b["width"] for b in br) / 50.0
    lo, hi = v.min(axis=0), v.max(axis=0)
    from matplotlib.path import Path
    gx = lo[0] + h * (np.arange(int(np.ceil((hi[0] - lo[0]) / h))) + 0.5)
    gy = lo[1] + h * (np.arange(int(np.ceil((hi[1] - lo[1]) / h))) + 0.5)
    X, Y = np.meshgrid(gx, gy)
    pts = np.c_[X.ravel(), Y.ravel()]
    inside = Path(v).contains_points(pts)
    owned = np.zeros(len(br))
    for p in pts[inside]:
        owned[of_point(p)] += h * h
    areal = np.zeros((len(steps), len(br)))
    for f in range(len(steps)):
        for i in np.where(ids[f][:capacity] >= 0)[0]:
            b = of_point(x[f][i, :2])
            if b >= 0:
                areal[f, b] += np.pi * r[f][i] ** 2
    areal /= owned
    return dp.tolist(), areal.tolist(), "rebuilt from wall_shear_stress and wall_normal_stress"


# The commit from which the engine's pressure drops count the held particles' load (the fluid's
# force and the mobile particles' pair forces); trajectories of earlier builds hold the fluid's part.
LOAD_FIX = "0344c5d"
# From this commit a mobile particle's pair load goes to its own branch in pressure_drop_branches
# (before, to the branches of the wall particles it touched: corner deposits split between two).
BRANCH_FIX = "ba19fff"


def has_commit(describe, fix):
    """Whether a build (git describe of its binary) contains commit `fix`; unknown commits count as older."""
    commit = describe.replace("-dirty", "").split("-g")[-1]
    here = os.path.dirname(os.path.abspath(__file__))
    return subprocess.run(["git", "merge-base", "--is-ancestor", fix, commit], cwd=here,
                          capture_output=True).returncode == 0


def momentum_drop(scene, F, ids, capacity):
    """The particle pressure drop from the per-particle forces of each frame: the solids' force on the
    fluid along the inlet's inward normal s over the inlet section A (width x depth),
    -(sum_held F + sum_mobile F) . s / A. A held particle's recorded force is the one it exerts on the
    fluid; a mobile one's is its non-hydrodynamic force, which a quasi-static particle passes on to
    the fluid. Pair forces among mobile particles cancel, so this is the held particles' load of
    docs/channels.md ("Outputs") when the mobile particles carry no external force (None then)."""
    import tomllib
    t = tomllib.loads(scene)
    if t.get("forces", {}).get("external_force"):
        return None
    w = t["walls"]
    inlet = branches(w["outline"], w["openings"], w["inlet"])[0][0]  # branch 0: d the inlet's inward normal
    s_in = inlet["d"]
    area = inlet["width"] * w.get("depth", 2.0 * w.get("radius", 1.0))
    out = []
    for fr in range(F.shape[0]):
        use = np.r_[ids[fr][:capacity] >= 0, np.ones(F.shape[1] - capacity, bool)]
        out.append(float(-(F[fr][use, :2].sum(axis=0) @ s_in) / area))
    return out


def extract(path):
    f = h5py.File(path, "r")
    obs = f["observables"]
    part = f["particles/all"]
    steps = part["position/step"][:]
    times = part["position/time"][:]
    ids = part["id/value"][:]
    p = f["parameters/stokesian"]
    scene = p["scene"][()].decode()
    build = {("describe" if k == "git" else k): p[k][()].decode() for k in ("git", "version", "compiler", "build_type", "model")}
    capacity = int(next(l.split("=")[1] for l in scene.splitlines() if l.strip().startswith("capacity")))
    series = {"step": steps.tolist(), "time": times.tolist()}
    for name in ("pressure_drop_particles", "particles_present", "inflow_inserted", "inflow_removed",
                 "inflow_deferred", "min_gap", "overlaps"):
        series[name] = obs[name + "/value"][:].tolist()
    series["areal_fraction_sections"] = obs["areal_fraction_sections/value"][:].tolist()
    series["wall_force"] = obs["wall_force/value"][:].tolist()
    x = part["position/value"]
    r = part["radius/value"]
    series["deposited"] = [deposited(x[k], r[k], ids[k], capacity) for k in range(len(steps))]
    series["pressure_drop_branches"], series["areal_fraction_branches"], how = branch_series(
        scene, obs, x, r, ids, capacity, steps)
    # The held particles' load, from the per-particle forces; files of builds before LOAD_FIX record
    # the fluid's force alone: their total is replaced by it and their per-branch drops dropped.
    mom = momentum_drop(scene, part["force/value"][:], ids, capacity)
    drop = {"recorded_is_load": has_commit(build["describe"], LOAD_FIX),
            "branches_by_mobile_particle": has_commit(build["describe"], BRANCH_FIX)}
    if mom is not None:
        rec = np.array(series["pressure_drop_particles"])
        drop["max_abs_difference_recorded_momentum"] = float(np.max(np.abs(rec - np.array(mom))))
        if not drop["recorded_is_load"]:
            series["pressure_drop_particles_fluid_only"] = series["pressure_drop_particles"]
            series["pressure_drop_particles"] = mom
            del series["pressure_drop_branches"]
            how = f"not available (written before {LOAD_FIX}: the fluid's force only)"
    elif not drop["recorded_is_load"]:
        raise SystemExit(f"{path}: written before {LOAD_FIX} with external forces: its drop cannot be rebuilt")
    if drop["recorded_is_load"] and not drop["branches_by_mobile_particle"] and "pressure_drop_branches" in series:
        if np.array(series["pressure_drop_branches"]).shape[1] > 1:  # one branch: equal to the total either way
            del series["pressure_drop_branches"]
            how = f"not available (written before {BRANCH_FIX}: corner deposits split between branches)"
    # The last frame's configuration (present spheres and walls) for the picture.
    last = len(steps) - 1
    keep = np.where(ids[last] >= 0)[0]
    snap = {"x": x[last][keep, 0].tolist(), "y": x[last][keep, 1].tolist(), "radius": r[last][keep].tolist(),
            "wall": (keep >= capacity).tolist()}
    return {"file": path, "build": build, "frames": len(steps), "last_step": int(steps[-1]), "last_time": float(times[-1]),
            "capacity": capacity, "scene": scene, "contact_gap": CONTACT, "series": series,
            "snapshot": snap, "branches_source": how, "pressure_drop": drop}


def main():
    args = sys.argv[1:]
    out = "bench/results/fouling.json"
    if "--out" in args:
        k = args.index("--out")
        out = args[k + 1]
        del args[k:k + 2]
    note = ""
    if "--note" in args:
        k = args.index("--note")
        note = args[k + 1]
        del args[k:k + 2]
    if not args:
        sys.exit(__doc__)
    commit = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True, text=True).stdout.strip()
    # "git": the tree this summary was made in; each run's "build" holds what its binary recorded.
    result = {"git": commit,
              "machine": {"node": platform.node(), "processor": platform.processor(), "python": platform.python_version()},
              "note": note, "runs": {}}
    for a in args:
        name, path = a.split("=", 1)
        result["runs"][name] = extract(path)
        r = result["runs"][name]
        print(f"{name}: {r['frames']} frames to step {r['last_step']} (t = {r['last_time']:.4g})")
    json.dump(result, open(out, "w"), indent=1)
    print("wrote", out)


main()
