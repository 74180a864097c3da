#!/usr/bin/env python3
"""Chart of a sweep's summary table (docs/sweeps.md): an observable against a swept key, with
error bars, one line per value of another swept key.

    stokesian plot DIR --y OBSERVABLE [--x KEY] [--series KEY] [--out DIR/OBSERVABLE.png]
    python3 tools/stokesian_sweep_plot.py DIR|DIR/summary.csv --y OBSERVABLE [same options]

--y: an observable of the summary (its columns NAME_mean, NAME_se; a component of a vector
observable as NAME[c]) or any numeric column (e.g. wall_seconds, drawn without error bars).
--x: a swept key (default: the first one that is not "replica"). --series: a swept key whose
values give separate lines (default: every other swept key with more than one value, combined).
Replicas: each run is drawn as a small point with its own standard error; the line joins the
replica means, whose error bar is the standard deviation of the replicas over sqrt(R) (R >= 2),
else the run's own standard error. Only finished runs (status "done") are drawn.
Needs numpy and matplotlib (Debian: python3-numpy python3-matplotlib).
Exit status: 0 written, 1 usage (a column the table does not have), 4 unreadable table or image
not written.
"""
import argparse
import csv
import math
import os
import sys

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as e:  # pragma: no cover - environment problem
    sys.stderr.write(f"stokesian_sweep_plot.py: {e}; needs numpy and matplotlib "
                     "(Debian: python3-numpy python3-matplotlib)\n")
    sys.exit(4)

FIXED = ("status", "exit_code", "wall_seconds", "attempts", "message")


def number(s):
    try:
        return float(s)
    except ValueError:
        return math.nan


def main():
    ap = argparse.ArgumentParser(description="Chart a sweep's summary table (docs/sweeps.md).")
    ap.add_argument("table", help="the sweep's folder or its summary.csv")
    ap.add_argument("--y", required=True, help="observable (NAME for NAME_mean/NAME_se) or numeric column")
    ap.add_argument("--x", help="swept key on the horizontal axis (default: the first swept key)")
    ap.add_argument("--series", help="swept key giving one line per value (default: the other swept keys)")
    ap.add_argument("--out", help="image file (default: DIR/<y>.png)")
    ap.add_argument("--logx", action="store_true")
    ap.add_argument("--logy", action="store_true")
    a = ap.parse_args()

    path = os.path.join(a.table, "summary.csv") if os.path.isdir(a.table) else a.table
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
            header = list(rows[0].keys()) if rows else []
    except OSError as e:
        sys.stderr.write(f"stokesian_sweep_plot.py: {path}: {e.strerror}\n")
        return 4
    if not rows:
        sys.stderr.write(f"stokesian_sweep_plot.py: {path}: the table has no runs\n")
        return 4
    swept = header[1:header.index("status")] if "status" in header else []
    keys = [k for k in swept if k != "replica"]
    if a.y + "_mean" in header:
        ycol, ecol = a.y + "_mean", a.y + "_se"
    elif a.y in header and a.y not in ("run", "message", "status"):
        ycol, ecol = a.y, None
    else:
        obs = sorted({c[:-5] for c in header if c.endswith("_mean")})
        sys.stderr.write(f"stokesian_sweep_plot.py: --y {a.y}: not in {path}; observables: {', '.join(obs)}; "
                         f"numeric columns: {', '.join(c for c in header if c in FIXED[1:4])}\n")
        return 1
    x = a.x or (keys[0] if keys else None)
    if x is None or x not in swept:
        sys.stderr.write(f"stokesian_sweep_plot.py: --x {x}: not a swept key of {path} (swept: {', '.join(keys)})\n")
        return 1
    if a.series and a.series not in keys:
        sys.stderr.write(f"stokesian_sweep_plot.py: --series {a.series}: not a swept key (swept: {', '.join(keys)})\n")
        return 1
    others = [a.series] if a.series else [k for k in keys if k != x and len({r[k] for r in rows}) > 1]
    done = [r for r in rows if r.get("status") == "done"]
    if not done:
        sys.stderr.write(f"stokesian_sweep_plot.py: {path}: no finished run to draw\n")
        return 4

    groups = {}
    for r in done:
        groups.setdefault(tuple(r[k] for k in others), []).append(r)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for gi, (g, rs) in enumerate(sorted(groups.items())):
        colour = f"C{gi % 10}"
        label = ", ".join(f"{k} = {v}" for k, v in zip(others, g)) or None
        xs = sorted({number(r[x]) for r in rs})
        means, errs = [], []
        for xv in xs:
            at = [r for r in rs if number(r[x]) == xv]
            ys = np.array([number(r[ycol]) for r in at])
            es = np.array([number(r[ecol]) for r in at]) if ecol else np.zeros(len(at))
            ax.errorbar([xv] * len(at), ys, yerr=es if ecol else None, fmt="o", ms=3, color=colour, alpha=0.35,
                        elinewidth=0.8, capsize=2)
            ok = np.isfinite(ys)
            means.append(ys[ok].mean() if ok.any() else math.nan)
            if ok.sum() >= 2:
                errs.append(ys[ok].std(ddof=1) / math.sqrt(ok.sum()))
            else:
                errs.append(es[ok][0] if ok.any() and ecol else 0.0)
        ax.errorbar(xs, means, yerr=errs, fmt="-s", ms=5, color=colour, capsize=3, label=label)
    ax.set_xlabel(x)
    ax.set_ylabel(a.y + (" (time average)" if ecol else ""))
    if a.logx:
        ax.set_xscale("log")
    if a.logy:
        ax.set_yscale("log")
    ax.set_title(f"{os.path.basename(os.path.dirname(os.path.abspath(path)))}: {len(done)} of {len(rows)} runs"
                 + ("; replicas: points, their mean: line" if "replica" in swept else ""), fontsize=9)
    if groups and others:
        ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = a.out or os.path.join(os.path.dirname(os.path.abspath(path)), a.y.replace("/", "_") + ".png")
    try:
        fig.savefig(out, dpi=110)
    except OSError as e:
        sys.stderr.write(f"stokesian_sweep_plot.py: {out}: {e.strerror}\n")
        return 4

    return 0


if __name__ == "__main__":
    sys.exit(main())
