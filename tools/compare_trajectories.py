#!/usr/bin/python3
"""Compare two H5MD trajectories dataset by dataset: every numeric dataset below /particles and
/observables must exist in both with the same shape and the same values, bit for bit (NaN equal to
NaN). /parameters and /h5md (build information, model text) are not compared. Prints each
difference with its largest absolute deviation; exit status 1 when any differs.

Use it to show that a change leaves results unchanged: run one scene with both builds and compare.

usage: compare_trajectories.py A.h5 B.h5
"""
import sys

import h5py
import numpy as np


def datasets(group, path=""):
    out = {}
    for name, item in group.items():
        p = f"{path}/{name}"
        if isinstance(item, h5py.Group):
            out.update(datasets(item, p))
        else:
            out[p] = item
    return out


a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
da, db = datasets(a), datasets(b)
bad = 0
for key in sorted(set(da) | set(db)):
    if key.startswith("/parameters") or key.startswith("/h5md"):
        continue
    if key not in da or key not in db:
        print(f"only in {'A' if key in da else 'B'}: {key}")
        bad += 1
        continue
    x, y = np.asarray(da[key][()]), np.asarray(db[key][()])
    if x.shape != y.shape:
        print(f"shape {key}: {x.shape} vs {y.shape}")
        bad += 1
    elif x.dtype.kind in "fi" and not np.array_equal(x, y, equal_nan=True):
        print(f"differs {key}: max |A - B| = {np.nanmax(np.abs(x - y)):.3e}")
        bad += 1
print(f"{sys.argv[1]} vs {sys.argv[2]}: " + ("identical" if bad == 0 else f"{bad} differences"))
sys.exit(1 if bad else 0)
