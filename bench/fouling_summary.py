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
    # The last frame's configuration (present spheres and walls) for the picture.
    last = len(steps) - 1
    keep = np.where(ids[last] >= 0)[0]
    snap = {"x": x[last][keep, 0].tolist(), "y": x[last][keep, 1].tolist(), "radius": r[last][keep].tolist(),
            "wall": (keep >= capacity).tolist()}
    return {"file": path, "build": build, "frames": len(steps), "last_step": int(steps[-1]), "last_time": float(times[-1]),
            "capacity": capacity, "scene": scene, "contact_gap": CONTACT, "series": series,
            "snapshot": snap}


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
