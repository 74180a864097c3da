#!/usr/bin/python3
"""Charts of steady-shear rheology against the Peclet number from a sweep's summary table.

    /usr/bin/python3 bench/plot_rheology.py DIR [--out FILE.png] [--json FILE.json]

DIR is the folder of `stokesian sweep` over `flow.peclet` (e.g. configs/sweeps/hard_sphere_peclet.toml,
docs/rheology.md), whose summary.csv holds, per run, the window means and blocked standard errors
of relative_viscosity[_part], N1[_part] and N2[_part]. Replicas of one Pe are combined: the mean of
their means, with standard error sqrt(sum se_r^2) / R. Normal-stress differences are shown as
N / (mu rate) with mu rate = Pe kT / (6 pi a^3) (the scene's Pe convention; kT and mu from the
first run's scene). Published values, where tests/data/rheology_references.json holds them, are
drawn as open symbols with their source in the legend.
"""
import argparse
import csv
import json
import math
import os
import sys
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PARTS = ["", "_hydrodynamic", "_brownian", "_interparticle"]
LABEL = {"": "total", "_hydrodynamic": "hydrodynamic (+ fluid)", "_brownian": "Brownian", "_interparticle": "interparticle"}


def load(folder):
    path = os.path.join(folder, "summary.csv") if os.path.isdir(folder) else folder
    rows = [r for r in csv.DictReader(open(path)) if r.get("status") == "done"]
    if not rows:
        sys.exit(f"plot_rheology: {path}: no finished runs")
    if "flow.peclet" not in rows[0]:
        sys.exit(f"plot_rheology: {path}: the sweep does not vary flow.peclet")
    base = os.path.dirname(path)
    scene = tomllib.load(open(os.path.join(base, rows[0]["run"], "scene.toml"), "rb"))
    kT, mu = scene["fluid"]["kT"], scene["fluid"]["viscosity"]
    return rows, kT, mu


def combine(rows, column):
    """Pe -> (mean, se, replicas) of a column over replicas."""
    by_pe = {}
    for r in rows:
        m, s = r.get(column + "_mean", ""), r.get(column + "_se", "")
        if m in ("", "nan"):
            continue
        by_pe.setdefault(float(r["flow.peclet"]), []).append((float(m), float(s) if s not in ("", "nan") else math.nan))
    out = {}
    for pe, vals in sorted(by_pe.items()):
        R = len(vals)
        out[pe] = (sum(v for v, _ in vals) / R, math.sqrt(sum(e * e for _, e in vals)) / R, R)
    return out


def references():
    path = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "rheology_references.json")
    try:
        data = json.load(open(path))
    except OSError:
        return []
    refs = []
    for key, d in data.items():
        if not isinstance(d, dict):
            continue
        vals = d.get("values")
        if isinstance(vals, list) and vals and isinstance(vals[0], dict) and "Pe" in vals[0]:
            refs.append((key, d.get("source", key), vals))
    return refs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--out", default="bench/results/rheology.png")
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    rows, kT, mu = load(a.folder)
    table = {}
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.3))
    for part in PARTS:
        c = combine(rows, "relative_viscosity" + part)
        if not c:
            continue
        pe = list(c)
        # The fluid's 1 is drawn with the hydrodynamic part, as published plots do.
        y = [c[p][0] + (1.0 if part == "_hydrodynamic" else 0.0) for p in pe]
        ax[0].errorbar(pe, y, yerr=[c[p][1] for p in pe], marker="o", capsize=3, label=LABEL[part])
        table["relative_viscosity" + part] = {str(p): c[p] for p in pe}
    for name, style in (("N1", "s"), ("N2", "^")):
        for part in ("", "_hydrodynamic", "_brownian"):
            c = combine(rows, name + part)
            if not c:
                continue
            pe = list(c)
            scale = [p * kT / (6 * math.pi) for p in pe]  # mu rate = Pe kT / (6 pi a^3)
            ax[1].errorbar(pe, [c[p][0] / s for p, s in zip(pe, scale)], yerr=[c[p][1] / s for p, s in zip(pe, scale)],
                           marker=style, capsize=3, ls="-" if part == "" else ":", label=f"{name} {LABEL[part]}")
            table[name + part + "_over_mu_rate"] = {str(p): (c[p][0] / s, c[p][1] / s, c[p][2]) for p, s in zip(pe, scale)}
    for key, source, vals in references():
        pe = [v["Pe"] for v in vals if "eta_r" in v]
        if pe:
            ax[0].plot(pe, [v["eta_r"] for v in vals if "eta_r" in v], "ko", mfc="none", label=source[:40])
    ax[0].set_xscale("log")
    ax[0].set_xlabel("Pe = 6 pi mu a^3 rate / kT")
    ax[0].set_ylabel("relative viscosity")
    ax[0].set_title("(a) eta_r and its parts")
    ax[0].legend(fontsize=8)
    ax[1].set_xscale("log")
    ax[1].axhline(0, color="0.6", lw=0.8)
    ax[1].set_xlabel("Pe")
    ax[1].set_ylabel("N / (mu rate)")
    ax[1].set_title("(b) normal-stress differences")
    ax[1].legend(fontsize=7)
    fig.suptitle(f"{os.path.abspath(a.folder)}: {len(rows)} finished runs; error bars: blocked standard errors")
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")
    if a.json:
        json.dump({"folder": os.path.abspath(a.folder), "kT": kT, "mu": mu, "series": table}, open(a.json, "w"), indent=1)
        print(f"wrote {a.json}")


if __name__ == "__main__":
    main()
