#!/usr/bin/python3
"""Charts of steady-shear rheology from a sweep's summary table, against the Peclet number or the volume fraction.

    /usr/bin/python3 bench/plot_rheology.py DIR [--out FILE.png] [--json FILE.json] [--check] [--merge OLD.json]

DIR is the folder of `stokesian sweep` over `flow.peclet` (Brownian suspensions, e.g.
configs/sweeps/hard_sphere_peclet.toml) or over `particles.volume_fraction` (the non-Brownian
limit, configs/sweeps/noncolloidal_phi.toml); docs/rheology.md. Its summary.csv holds, per run,
the window means and blocked standard errors of relative_viscosity[_part], N1[_part] and
N2[_part]. Replicas of one point are combined: the mean of their means, with standard error
sqrt(sum se_r^2) / R, or the replicas' scatter s_R / sqrt(R) when that is larger (a run's blocked
error misses what is slower than its window, e.g. structure at Pe < 1 that has not relaxed). Normal-stress differences are shown as N / (mu rate): against Pe with
mu rate = Pe kT / (6 pi a^3) (the scene's Pe convention; kT from the first run's scene), against
phi with mu and rate of the first run's scene. Published values, where
tests/data/rheology_references.json holds them (entries whose values have "Pe" or "phi" and
"eta_r"), are drawn as open symbols with their source in the legend.

--merge adds the points of an earlier chart's JSON at x values DIR has no finished run for (points
whose runs were made in another folder); the chart's title and the JSON's "merged" name them.

The JSON also holds the published qualitative shape as named checks (shape_checks); --check
exits 1 unless all pass (for full sweeps; the quick CI sweep is too short to show the shape).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PARTS = ["", "_hydrodynamic", "_brownian", "_interparticle"]
COLOR = {"": "C0", "_hydrodynamic": "C1", "_brownian": "C2", "_interparticle": "C3"}
LABEL = {"": "total", "_hydrodynamic": "hydrodynamic (+ fluid)", "_brownian": "Brownian", "_interparticle": "interparticle"}


AXES = {"flow.peclet": ("Pe", "Pe = 6 pi mu a^3 rate / kT", True),
        "particles.volume_fraction": ("phi", "volume fraction phi", False)}


def load(folder):
    path = os.path.join(folder, "summary.csv") if os.path.isdir(folder) else folder
    rows = [r for r in csv.DictReader(open(path)) if r.get("status") == "done"]
    if not rows:
        sys.exit(f"plot_rheology: {path}: no finished runs")
    xkey = next((k for k in AXES if k in rows[0]), None)
    if xkey is None:
        sys.exit(f"plot_rheology: {path}: the sweep varies neither flow.peclet nor particles.volume_fraction")
    base = os.path.dirname(path)
    scene = tomllib.load(open(os.path.join(base, rows[0]["run"], "scene.toml"), "rb"))
    return rows, xkey, scene


def combine(rows, column, xkey):
    """x -> (mean, se, replicas) of a column over replicas."""
    by_x = {}
    for r in rows:
        m, s = r.get(column + "_mean", ""), r.get(column + "_se", "")
        if m in ("", "nan"):
            continue
        by_x.setdefault(float(r[xkey]), []).append((float(m), float(s) if s not in ("", "nan") else math.nan))
    out = {}
    for x, vals in sorted(by_x.items()):
        R = len(vals)
        mean = sum(v for v, _ in vals) / R
        se = math.sqrt(sum(e * e for _, e in vals)) / R
        if R > 1:  # the replicas' own scatter, when it exceeds what their blocked errors predict
            spread = math.sqrt(sum((v - mean) ** 2 for v, _ in vals) / (R - 1) / R)
            se = max(se, spread)
        out[x] = (mean, se, R)
    return out


def references(xname):
    path = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "rheology_references.json")
    try:
        data = json.load(open(path))
    except OSError:
        return []
    refs = []
    for key, d in data.get("datasets", {}).items():
        if not isinstance(d, dict):
            continue
        vals = d.get("values")
        if isinstance(vals, list) and vals and isinstance(vals[0], dict) and xname in vals[0]:
            refs.append((key, d.get("source", key), vals))
    return refs


def shape_checks(table, xname):
    """The published qualitative shape (docs/rheology.md), each check with the numbers it used.

    Pe: shear thinning from the lowest Pe to a minimum, then thickening driven by the hydrodynamic
    part (Foss & Brady 2000); N1 > 0 at low Pe and < 0 at high Pe; N2 < 0 everywhere.
    phi (non-Brownian): eta_r increases with phi; N1 < 0 and N2 < 0 from phi = 0.3 (Seto & Giusteri
    2018; Wilson). A difference counts when it exceeds twice its standard error."""
    def series(name):
        return {float(k): v for k, v in table.get(name, {}).items()}

    def differs(a, b):  # a > b beyond 2 combined standard errors
        return a[0] - b[0] > 2.0 * math.hypot(a[1], b[1])

    eta, hyd = series("relative_viscosity"), series("relative_viscosity_hydrodynamic")
    n1, n2 = series("N1_over_mu_rate"), series("N2_over_mu_rate")
    out = {}
    if not eta:
        return out
    xs = sorted(eta)
    if xname == "Pe":
        if xs[0] > 1.0 or xs[-1] < 100.0 or len(xs) < 4:
            # The shape spans Pe <= 1 to >= 100: fewer points cannot show it either way.
            return {"not_judged": {"pass": False, "reason": "needs Pe <= 1 and >= 100 and at least 4 points",
                                   "Pe": xs}}
        xmin = min(xs, key=lambda x: eta[x][0])
        out["shear_thinning"] = {"pass": xmin != xs[0] and differs(eta[xs[0]], eta[xmin]),
                                 "eta_at_lowest_Pe": eta[xs[0]], "Pe_of_minimum": xmin, "eta_at_minimum": eta[xmin]}
        out["hydrodynamic_thickening"] = {
            "pass": xmin != xs[-1] and differs(eta[xs[-1]], eta[xmin]) and bool(hyd) and differs(hyd[xs[-1]], hyd[xmin]),
            "eta_at_highest_Pe": eta[xs[-1]], "hydrodynamic_at_highest_Pe": hyd.get(xs[-1]),
            "hydrodynamic_at_minimum": hyd.get(xmin)}
        pos = [x for x in sorted(n1) if n1[x][0] > 2 * n1[x][1]]
        neg = [x for x in sorted(n1) if -n1[x][0] > 2 * n1[x][1]]
        out["N1_changes_sign"] = {"pass": bool(pos) and bool(neg) and max(pos) < min(neg), "Pe_N1_positive": pos,
                                  "Pe_N1_negative": neg}
        out["N2_negative"] = {"pass": bool(n2) and all(v[0] < 0 for v in n2.values()),
                              "N2_over_mu_rate": {str(x): n2[x] for x in sorted(n2)}}
    else:
        out["eta_increases_with_phi"] = {"pass": all(differs(eta[b], eta[a]) for a, b in zip(xs, xs[1:])),
                                         "eta": {str(x): eta[x] for x in xs}}
        dense = [x for x in sorted(n1) if x >= 0.3 - 1e-9]
        out["N1_N2_negative_from_phi_0.3"] = {
            "pass": bool(dense) and all(n1[x][0] < 0 and x in n2 and n2[x][0] < 0 for x in dense), "phi": dense}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--out", default="bench/results/rheology.png")
    ap.add_argument("--json", default="")
    ap.add_argument("--check", action="store_true", help="exit 1 unless every shape check passes (full sweeps)")
    ap.add_argument("--merge", action="append", default=[], metavar="OLD.json",
                    help="add the points of an earlier chart's JSON (same swept key) at x values the folder lacks")
    a = ap.parse_args()
    rows, xkey, scene = load(a.folder)
    xname, xlabel, logx = AXES[xkey]
    fluid, flow = scene.get("fluid", {}), scene.get("flow", {})
    kT, mu = fluid.get("kT", 0.0), fluid.get("viscosity", 1.0)

    def mu_rate(x):
        return x * kT / (6 * math.pi) if xname == "Pe" else mu * flow["rate"]

    table = {}
    for part in PARTS:
        c = combine(rows, "relative_viscosity" + part, xkey)
        if c:
            table["relative_viscosity" + part] = {str(x): c[x] for x in c}
    for name in ("N1", "N2"):
        for part in PARTS:
            c = combine(rows, name + part, xkey)
            if c:
                table[name + part + "_over_mu_rate"] = {
                    str(x): (c[x][0] / mu_rate(x), c[x][1] / mu_rate(x), c[x][2]) for x in c}
    # Points of an earlier chart's JSON whose runs are not in the folder (--merge), for x values the
    # folder does not have.
    merged = {}
    for path in a.merge:
        old = json.load(open(path))
        if old.get("x") != xkey:
            sys.exit(f"plot_rheology: {path}: varies {old.get('x')}, not {xkey}")
        for series, vals in old.get("series", {}).items():
            t = table.setdefault(series, {})
            for x, v in vals.items():
                if x not in t:
                    t[x] = tuple(v)
                    merged.setdefault(path, set()).add(float(x))
    for series in table:
        table[series] = dict(sorted(table[series].items(), key=lambda kv: float(kv[0])))

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.3))
    for part in PARTS:
        c = table.get("relative_viscosity" + part)
        if not c:
            continue
        xs = [float(x) for x in c]
        # The fluid's 1 is drawn with the hydrodynamic part, as published plots do.
        y = [v[0] + (1.0 if part == "_hydrodynamic" else 0.0) for v in c.values()]
        ax[0].errorbar(xs, y, yerr=[v[1] for v in c.values()], marker="o", capsize=3, color=COLOR[part], label=LABEL[part])
    for name, style in (("N1", "s"), ("N2", "^")):
        for part in PARTS:
            c = table.get(name + part + "_over_mu_rate")
            if not c:
                continue
            ax[1].errorbar([float(x) for x in c], [v[0] for v in c.values()], yerr=[v[1] for v in c.values()],
                           marker=style, capsize=3, color=COLOR[part], ls="-" if name == "N1" else "--",
                           lw=2.0 if part == "" else 1.0, label=f"{name} {LABEL[part].replace(' (+ fluid)', '')}")
    for key, source, vals in references(xname):
        pts = [v for v in vals if "eta_r" in v]
        if pts:
            ax[0].plot([v[xname] for v in pts], [v["eta_r"] for v in pts], "ko", mfc="none", label=source[:40])
    for axis in ax:
        if logx:
            axis.set_xscale("log")
        axis.set_xlabel(xlabel)
    ax[0].set_ylabel("relative viscosity")
    ax[0].set_title("(a) eta_r and its parts")
    ax[0].legend(fontsize=8)
    ax[1].axhline(0, color="0.6", lw=0.8)
    ax[1].set_ylabel("N / (mu rate)")
    ax[1].set_title("(b) normal-stress differences (N1 solid, N2 dashed)")
    ax[1].legend(fontsize=7)
    note = "; merged: " + ", ".join(f"{xname} = {', '.join('%g' % x for x in sorted(v))} from {os.path.basename(k)}"
                                    for k, v in merged.items()) if merged else ""
    fig.suptitle(f"{os.path.basename(os.path.abspath(a.folder))}: {len(rows)} finished runs{note}; error bars: standard errors (blocked, or the replicas' scatter when larger)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")
    checks = shape_checks(table, xname)
    for name, c in checks.items():
        print(f"{'pass' if c['pass'] else 'FAIL'}: {name}")
    if a.json:
        try:  # the source tree the chart was made from (the runs record their scenes, not the binary)
            git = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=os.path.dirname(os.path.abspath(__file__)),
                                 capture_output=True, text=True, check=True).stdout.strip()
        except (OSError, subprocess.CalledProcessError):
            git = "unknown"
        json.dump({"git": git, "folder": os.path.abspath(a.folder), "x": xkey, "runs": len(rows), "kT": kT, "mu": mu,
                   "merged": {k: sorted(v) for k, v in merged.items()},
                   "series": table, "shape_checks": checks}, open(a.json, "w"), indent=1)
        print(f"wrote {a.json}")
    if a.check and not all(c["pass"] for c in checks.values()):
        sys.exit(1)


if __name__ == "__main__":
    main()
