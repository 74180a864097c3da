#!/usr/bin/python3
"""Checks of stokesian trajectories with the tools users have (h5py, MDAnalysis); run by
tests/test_outputs.cpp. Usage: check_outputs.py <check> FILE [args]; exit status 0 = pass."""
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))

LENGTH, TIME = "a", "mu a+3 kT-1"


def fail(msg):
    print("check_outputs:", msg, file=sys.stderr)
    sys.exit(1)


def unit(ds):
    u = ds.attrs.get("unit")
    return u.decode() if isinstance(u, bytes) else u


def check_mdanalysis(path, author):
    with h5py.File(path, "r") as f:
        all_ = f["particles/all"]
        expected = {"position": LENGTH, "radius": LENGTH, "box/edges": LENGTH, "velocity": "kT mu-1 a-2",
                    "force": "kT a-1"}
        for name, u in expected.items():
            if unit(all_[name + "/value"]) != u:
                fail(f"{name}/value unit {unit(all_[name + '/value'])!r}, expected {u!r}")
        if unit(all_["position/time"]) != TIME:
            fail(f"position/time unit {unit(all_['position/time'])!r}")
        if "unit" in all_["image/value"].attrs:
            fail("image is a pure number and must carry no unit")
        for name, u in {"min_gap": LENGTH, "pair_energy": "kT", "dt": TIME}.items():
            if unit(f["observables"][name]["value"]) != u or unit(f["observables"][name]["time"]) != TIME:
                fail(f"observables/{name} units")
        if f["h5md/author"].attrs["name"].decode() != author:
            fail(f"author {f['h5md/author'].attrs['name']!r}, expected {author!r}")
        pos = f["particles/all/position/value"][:]
        time = f["particles/all/position/time"][:]
        edges = f["particles/all/box/edges/value"][:]
        radius = f["particles/all/radius/value"][0]
    from stokesian_mda import universe  # tools/stokesian_mda.py, as docs/output.md shows

    u = universe(path)
    if u.trajectory.n_frames != len(pos):
        fail(f"MDAnalysis sees {u.trajectory.n_frames} frames, h5py {len(pos)}")
    if u.trajectory.units["length"] != LENGTH or u.trajectory.units["time"] != TIME:
        fail(f"MDAnalysis units {u.trajectory.units}")
    if not np.allclose(u.atoms.radii, radius):
        fail("radii differ")
    for k, ts in enumerate(u.trajectory):
        # MDAnalysis keeps float32 positions.
        if not np.allclose(ts.positions, pos[k], rtol=1e-6, atol=1e-5):
            fail(f"frame {k}: positions differ")
        if abs(ts.time - time[k]) > 1e-12 * max(1.0, abs(time[k])):
            fail(f"frame {k}: time {ts.time} != {time[k]}")
        lengths = np.linalg.norm(edges[k], axis=1)
        if not np.allclose(ts.dimensions[:3], lengths) or not np.allclose(ts.dimensions[3:], 90.0):
            fail(f"frame {k}: box {ts.dimensions}")
    print(f"MDAnalysis and h5py agree on {len(pos)} frames; units {u.trajectory.units}")


def check_author(path, author):
    with h5py.File(path, "r") as f:
        got = f["h5md/author"].attrs["name"].decode()
    if got != author:
        fail(f"author {got!r}, expected {author!r}")


def check_msd(path, D):
    D = float(D)
    with h5py.File(path, "r") as f:
        x = f["particles/all/position/value"][:]
        img = f["particles/all/image/value"][:]
        edges = f["particles/all/box/edges/value"][:]
        t = f["particles/all/position/time"][:]
    L = np.diagonal(edges[0])
    u = x + np.einsum("fnk,fkc->fnc", img, edges)  # position + image . box edges
    jumps_wrapped = np.abs(np.diff(x, axis=0)).max()
    jumps_unwrapped = np.abs(np.diff(u, axis=0)).max()
    crossings = np.abs(np.diff(img, axis=0)).sum()
    print(f"{crossings} face crossings; largest step wrapped {jumps_wrapped:.3f}, unwrapped {jumps_unwrapped:.3f}")
    if crossings < 20:
        fail("too few boundary crossings to test anything")
    if jumps_wrapped < 0.5 * L.min():
        fail("wrapped positions never jump: are they wrapped?")
    if jumps_unwrapped > 0.25 * L.min():
        fail("unwrapped trajectory jumps")
    dt = t[1] - t[0]
    for lag in (1, 5, 20):
        d = u[lag:] - u[:-lag]
        msd = (d ** 2).sum(axis=2).mean()
        expected = 6 * D * lag * dt
        # samples: frames x particles, overlapping windows; 3 sigma of the mean for independent
        # windows of one lag (relative variance 2/3 per sample) is far inside 15 %.
        n_independent = (len(u) // lag) * u.shape[1]
        tol = max(0.15, 4 * math.sqrt(2.0 / 3.0 / n_independent))
        print(f"lag {lag}: MSD {msd:.4f}, 6 D t = {expected:.4f}")
        if abs(msd / expected - 1) > tol:
            fail(f"MSD at lag {lag}: {msd} vs 6 D t = {expected}")


def check_integers(path, *datasets):
    with h5py.File(path, "r") as f:
        for name in datasets:
            if f[name].dtype.kind != "i":
                fail(f"{name} has dtype {f[name].dtype}, expected integers")


def check_same(a, b, *datasets):
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        for name in datasets:
            if not np.array_equal(fa[name][:], fb[name][:]):
                fail(f"{name} differs between {a} and {b}")


def check_msd_tool(path):
    """tools/stokesian_msd.py on a free-draining Brownian slit: D = D0 in every bin and direction,
    the wall particles left out, standard errors as for independent Gaussian steps at lag 1."""
    import json
    import tempfile
    import stokesian_msd
    with h5py.File(path, "r") as f:
        x = f["particles/all/position/value"][:]
    moving = int((np.abs(x[-1] - x[0]).max(axis=1) > 0).sum())
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "msd.json")
        if stokesian_msd.main([path, "--fold", "--bins", "0,1,2", "--lags", "1,4", "--blocks", "8", "--json", out]) != 0:
            fail("stokesian_msd.py refused a valid run")
        res = json.load(open(out))
        if res["meta"]["mobile"] != moving or moving == x.shape[1]:
            fail(f"mobile particles {res['meta']['mobile']}, moving {moving} of {x.shape[1]} (walls must be left out)")
        for r in res["rows"]:
            for d, se in zip(r["D"], r["se"]):
                # Free draining: every sample's mean is D0 exactly (Euler-Maruyama, constant mobility).
                if not (abs(d - 1) <= 4.5 * se and abs(d - 1) < 0.15):
                    fail(f"lag {r['lag_frames']} bin {r['bin']}: D/D0 = {d:.4f} (s.e. {se:.4f}), expected 1")
        if stokesian_msd.main([path, "--lags", "1", "--blocks", "20", "--json", out]) != 0:
            fail("stokesian_msd.py refused a valid run")
        r = json.load(open(out))["rows"][0]
        # Independent Gaussian steps: var(dx^2 / (2 D0 dt)) = 2 per sample.
        ideal = math.sqrt(2.0 / r["samples"])
        for se in r["se"]:
            if not 0.5 * ideal < se < 2.0 * ideal:
                fail(f"standard error {se:.5f} against {ideal:.5f} for independent samples")
        print(f"D/D0 = {r['D']} (s.e. {r['se']}, independent-sample value {ideal:.4f}); {moving} mobile")
    for bad in (["--bins", "1,0"], ["--blocks", "1"], ["--lags", "0"]):
        if stokesian_msd.main([path] + bad) != 2:
            fail(f"stokesian_msd.py accepted {bad}")
    if stokesian_msd.main([os.path.abspath(__file__)]) != 2:  # not an HDF5 file
        fail("stokesian_msd.py accepted a file that is not HDF5")


CHECKS = {"mdanalysis": check_mdanalysis, "author": check_author, "msd": check_msd, "integers": check_integers,
          "same": check_same, "msd_tool": check_msd_tool}

if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] not in CHECKS:
        fail("usage: check_outputs.py {" + ",".join(CHECKS) + "} FILE [args]")
    CHECKS[sys.argv[1]](*sys.argv[2:])
