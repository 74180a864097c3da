#!/usr/bin/python3
"""Chart the destabilisation runs (thesis s.5.3.4; docs/clusters.md): clusters against time.

    /usr/bin/python3 bench/plot_destab.py DIR [DIR ...] [--out FILE.png] [--json FILE.json]
                                          [--stokesian build/stokesian] [--gap 0.1] [--check]

Each DIR is a folder of `stokesian sweep` over configs/sweeps/destabilisation*.toml. For every
run its summary.csv marks done, the script reads the resolved scene (box, body forces),
the radii (N and the volume fraction) and the cluster analysis `trajectory.clusters.h5`, which it
makes with `stokesian clusters trajectory.h5 --gap GAP` when it is missing, has another bond gap or
leaves frames out.

Runs of one N and box are one group. Groups whose mean volume fractions phi = sum 4 pi a_i^3 /
(3 L^3) lie within 10 % of each other share a phi class, labelled by its mean to 2 significant
digits (the drawn radii move phi by ~1 % at N = 500 from the sweep's nominal value). Frames sit at the same steps in every run but at different times (RKF45),
so the replicas of a group are interpolated onto a common time grid (up to the shortest run) and
averaged; the band is their min..max.

Chart: (a) N_c/N against t, one colour per phi, one line style per N (solid the smallest, then
dashed, dotted: mean of the replicas, band = their range); top axis the thesis's time t U0/L0 = t F0 / (6 pi), F0 the body
force on a sphere of radius 1; (b)-(d) doublets, triplets and quadruplets per primary particle,
N_c,s/N, for the three smallest phi (the thesis's fig. 5.17), means over the smallest N's runs.

The JSON holds the runs' series, the group means and the checks the thesis states in words:
  n_independent  at every common time, |N_c/N(N) - N_c/N(500)| <= max(0.03, 2 x replica range)
                 for N = 1000, 2000 (the thesis: deviations from placement within 3 %, N negligible);
  faster_at_higher_phi  N_c/N at the end of the shortest run falls strictly with phi, and so does
                 the initial slope (least squares over the first thesis time unit);
  doublets_first  for each phi: doublets are the most numerous cluster class of size >= 2 over the
                 first thesis time unit (mean of N_c,s/N), and their initial formation rate (least
                 squares slope of N_c,s/N over the first tenth of that unit) is the largest of the
                 classes 2, 3, 4; the slopes over the whole first unit are reported beside them;
--check exits 1 unless all hold.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tomllib

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("dirs", nargs="+")
ap.add_argument("--out", default="bench/results/destab.png")
ap.add_argument("--json", default=None)
ap.add_argument("--stokesian", default="build/stokesian")
ap.add_argument("--gap", type=float, default=0.1)
ap.add_argument("--check", action="store_true")
args = ap.parse_args()
jpath = args.json or os.path.splitext(args.out)[0] + ".json"


def clusters_file(traj):
    """The cluster analysis of every frame of traj at --gap (made when missing or different)."""
    cf = os.path.splitext(traj)[0] + ".clusters.h5"
    if os.path.exists(cf):
        with h5py.File(traj) as t, h5py.File(cf) as f:
            frames = len(t["particles/all/position/step"])
            if abs(float(f.attrs["bond_gap"]) - args.gap) < 1e-12 and len(f["frames/step"]) == frames:
                return cf
    subprocess.run([args.stokesian, "clusters", traj, "--gap", repr(args.gap), "--out", cf],
                   check=True, stdout=subprocess.DEVNULL)
    return cf


runs = []
for d in args.dirs:
    table = os.path.join(d, "summary.csv")  # the sweep's own record of each run (docs/sweeps.md)
    if not os.path.exists(table):
        sys.exit(f"plot_destab: {table} missing: {d} is not a folder of a `stokesian sweep`")
    for row in csv.DictReader(open(table)):
        rd = os.path.join(d, row["run"])
        if row["status"] != "done":
            print(f"{rd}: {row['status']}, left out", file=sys.stderr)
            continue
        scene = tomllib.load(open(os.path.join(rd, "scene.toml"), "rb"))  # resolved: radii and forces listed
        traj = os.path.join(rd, "trajectory.h5")
        L = scene["domain"]["box"]
        V = L[0] * L[1] * L[2]
        with h5py.File(traj) as f:
            a = f["particles/all/radius/value"][0]
            x0 = f["particles/all/position/value"][0]
            git = f["parameters/stokesian/git"][()].decode()
        hy = scene["hydrodynamics"]
        model = "far field" if hy["model"] == "far_field" else f"{hy['model']} ({hy.get('lubrication', 'exact')})"
        N = len(a)
        phi_actual = float(np.sum(4 * math.pi * a ** 3 / 3) / V)
        cf = clusters_file(traj)
        with h5py.File(cf) as f:
            t = f["frames/time"][:]
            steps = int(f["frames/step"][-1])
            nc = f["frames/clusters"][:]
            largest = f["frames/largest"][:]
            hist = f["size_histogram"][:]
        cls = [hist[:, s - 1] if hist.shape[1] >= s else np.zeros(len(t)) for s in (2, 3, 4)]
        f0 = scene["forces"]["external_force"][0]
        runs.append(dict(
            dir=rd, model=model, N=N, box=float(L[0]), phi_actual=phi_actual, x0_sum=float(np.abs(x0).sum()),
            F0=float(math.sqrt(sum(x * x for x in f0)) / a[0] ** 3), git=git,
            wall_seconds=float(row["wall_seconds"]), steps=steps,
            t=t.tolist(), nc=(nc / N).tolist(), n2=(cls[0] / N).tolist(), n3=(cls[1] / N).tolist(),
            n4=(cls[2] / N).tolist(), largest=largest.tolist()))
if not runs:
    sys.exit("plot_destab: no finished runs in " + " ".join(args.dirs))

# Models: the one of most runs is the main one (panels a-d); runs of the others are compared with
# the main model's run that starts from the same positions (its twin).
models = sorted({r["model"] for r in runs}, key=lambda m: -sum(r["model"] == m for r in runs))
main_model = models[0]
F0 = runs[0]["F0"]
t_unit = 6 * math.pi / F0  # one thesis time unit L0/U0 in ours
# Groups: runs of one model, N and box (one sweep point); the volume fractions of the (N, box)
# points, clustered within 10 %, give the phi classes (the sweeps' nominal 0.01, 0.025, 0.05).
by_box = {}
for r in runs:
    by_box.setdefault((r["N"], r["box"]), []).append(r)
classes = []
for rs in sorted(by_box.values(), key=lambda rs: np.mean([r["phi_actual"] for r in rs])):
    p = float(np.mean([r["phi_actual"] for r in rs]))
    if classes and p <= 1.1 * classes[-1][0]:
        classes[-1][1].extend(rs)
    else:
        classes.append([p, list(rs)])
groups = {}  # (model, N, phi) -> runs
for _, rs in classes:
    phi = float(f"{np.mean([r['phi_actual'] for r in rs]):.2g}")
    for r in rs:
        r["phi"] = phi
        groups.setdefault((r["model"], r["N"], phi), []).append(r)
t_end = min(r["t"][-1] for r in runs)
tg = np.linspace(0.0, t_end, 200)
early = tg <= t_unit  # the first thesis time unit
initial = tg <= 0.1 * t_unit  # its first tenth: initial formation rates


def mean_of(rs, key):
    y = np.array([np.interp(tg, r["t"], r[key]) for r in rs])
    return y.mean(axis=0), y.min(axis=0), y.max(axis=0)


gm = {k: {key: mean_of(rs, key) for key in ("nc", "n2", "n3", "n4")} for k, rs in groups.items()}
phis = sorted({k[2] for k in groups})
Ns = sorted({k[1] for k in groups if k[0] == main_model})
base_N = Ns[0]


def model_checks(model):
    """The thesis's three statements for one model's runs."""
    out = {}
    Nm = sorted({k[1] for k in groups if k[0] == model})
    n0 = Nm[0]
    dev = []
    for (mo, N, phi), m in gm.items():
        if mo != model or N == n0 or (model, n0, phi) not in gm:
            continue
        b = gm[(model, n0, phi)]["nc"]
        spread = b[2] - b[1]
        d = np.abs(m["nc"][0] - b[0])
        dev.append(dict(N=N, phi=phi, max_deviation=float(d.max()), at_t=float(tg[d.argmax()]),
                        max_replica_range=float(spread.max()), ok=bool(np.all(d <= np.maximum(0.03, 2 * spread)))))
    if dev:
        out["n_independent"] = dict(ok=all(x["ok"] for x in dev), N_ref=n0, groups=dev)
    finals, slopes, df = {}, {}, []
    for phi in phis:
        m = gm.get((model, n0, phi))
        if m is None:
            continue
        finals[phi] = float(m["nc"][0][-1])
        slopes[phi] = float(np.polyfit(tg[early], m["nc"][0][early], 1)[0])
        sizes = ((2, "n2"), (3, "n3"), (4, "n4"))
        means = {s: float(m[k][0][early].mean()) for s, k in sizes}
        rates = {s: float(np.polyfit(tg[initial], m[k][0][initial], 1)[0] * t_unit) for s, k in sizes}
        unit_rates = {s: float(np.polyfit(tg[early], m[k][0][early], 1)[0] * t_unit) for s, k in sizes}
        df.append(dict(phi=phi, early_mean=means, initial_rate_per_thesis_time=rates,
                       first_unit_rate_per_thesis_time=unit_rates,
                       ok=means[2] > max(means[3], means[4]) and rates[2] > max(rates[3], rates[4])))
    fp, sp = [finals[p] for p in sorted(finals)], [slopes[p] for p in sorted(slopes)]
    if len(fp) > 1:  # needs two volume fractions
        out["faster_at_higher_phi"] = dict(
            ok=all(x > y for x, y in zip(fp, fp[1:])) and all(x > y for x, y in zip(sp, sp[1:])),
            N=n0, nc_at_end={str(p): v for p, v in finals.items()},
            initial_slope_per_thesis_time={str(p): v * t_unit for p, v in slopes.items()})
    out["doublets_first"] = dict(ok=bool(df) and all(x["ok"] for x in df), per_phi=df, window_thesis_time=1.0)
    return out


checks = {m: model_checks(m) for m in models}

# Other models against their twins (same N, box and initial positions) at the common end time.
comparison = []
for o in (r for r in runs if r["model"] != main_model):
    twins = [r for r in runs if r["model"] == main_model and r["N"] == o["N"] and r["box"] == o["box"]
             and abs(r["x0_sum"] - o["x0_sum"]) <= 1e-9 * o["x0_sum"]]
    if not twins:
        print(f"{o['dir']}: no {main_model} run from the same positions; not compared", file=sys.stderr)
        continue
    tw = twins[0]
    at = {key: dict(model=float(np.interp(t_end, o["t"], o[key])), twin=float(np.interp(t_end, tw["t"], tw[key])))
          for key in ("nc", "n2", "n3", "n4")}
    bonded = (1 - at["nc"]["model"], 1 - at["nc"]["twin"])
    comparison.append(dict(run=o["dir"], model=o["model"], twin=tw["dir"], twin_model=main_model, N=o["N"],
                           phi=o["phi"], t=float(t_end), at_t=at,
                           wall_seconds_per_unit_time=o["wall_seconds"] / o["t"][-1],
                           twin_wall_seconds_per_unit_time=tw["wall_seconds"] / tw["t"][-1],
                           mean_dt=o["t"][-1] / o["steps"], twin_mean_dt=tw["t"][-1] / tw["steps"],
                           aggregated_fraction_ratio=bonded[0] / bonded[1] if bonded[1] > 0 else float("nan")))

# Chart.
others = [m for m in models if m != main_model]
# Top row: (a) and (e); bottom row: (b)-(d).
fig = plt.figure(figsize=(16, 9.6))
gs = fig.add_gridspec(2, 6)
axs = [fig.add_subplot(gs[0, 0:3])] + [fig.add_subplot(gs[1, 2 * j:2 * j + 2]) for j in range(3)]
if others:
    axs.append(fig.add_subplot(gs[0, 3:6]))
style = dict(zip(Ns, ["-", "--", ":", "-."]))  # by N: smallest solid


def thesis_axis(ax):
    ax.set_xlabel("t [mu a^3 / kT]")
    sec = ax.secondary_xaxis("top", functions=(lambda x: x / t_unit, lambda x: x * t_unit))
    sec.set_xlabel("t U0 / L0 (thesis)")


ax = axs[0]
for i, phi in enumerate(phis):
    for N in Ns:
        k = (main_model, N, phi)
        if k not in gm:
            continue
        mu, lo, hi = gm[k]["nc"]
        n = len(groups[k])
        ax.plot(tg, mu, style[N], color=f"C{i}", label=f"phi = {phi:g}, N = {N}" + (f" ({n} runs)" if n > 1 else ""))
        if n > 1:
            ax.fill_between(tg, lo, hi, color=f"C{i}", alpha=0.2, lw=0)
ax.set_ylabel("N_c / N")
ax.set_title(f"(a) clusters per primary particle, {main_model}")
ax.legend(fontsize=7)
thesis_axis(ax)
for ax in axs[1 + min(3, len(phis)):4]:
    ax.set_visible(False)
for j, phi in enumerate(phis[:3]):
    ax = axs[j + 1]
    k = (main_model, base_N, phi)
    if k not in gm:
        continue
    for size, key in ((2, "n2"), (3, "n3"), (4, "n4")):
        mu, lo, hi = gm[k][key]
        ax.plot(tg, mu, color=f"C{size}", label=f"N_c,{size} / N")
        ax.fill_between(tg, lo, hi, color=f"C{size}", alpha=0.2, lw=0)
    ax.set_title(f"({'bcd'[j]}) size classes, phi = {phi:g}, N = {base_N}")
    ax.legend(fontsize=8)
    thesis_axis(ax)
if others:
    ax = axs[4]
    for i, phi in enumerate(phis):
        for model, ls in [(main_model, "-")] + [(m, "--") for m in others]:
            Nm = sorted(k[1] for k in gm if k[0] == model and k[2] == phi)
            if not Nm:
                continue
            k = (model, Nm[0], phi)
            mu, lo, hi = gm[k]["nc"]
            ax.plot(tg, mu, ls, color=f"C{i}", label=f"phi = {phi:g}, {model}, N = {Nm[0]} ({len(groups[k])})")
            if len(groups[k]) > 1:
                ax.fill_between(tg, lo, hi, color=f"C{i}", alpha=0.12, lw=0)
    ax.set_ylabel("N_c / N")
    ax.set_title("(e) near-field models (same starts)")
    ax.legend(fontsize=7)
    thesis_axis(ax)
fig.suptitle("Destabilisation: lognormal radii (mean 1, s.d. 0.065), alumina DLVO, body force "
             f"{F0:g} a^3 kT/a, periodic box, PME far field (FT); band = range over replicas", fontsize=10)
fig.tight_layout()
fig.savefig(args.out, dpi=110)

cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")), "unknown")
out = dict(description="destabilisation runs (plot_destab.py); times in mu a^3/kT, thesis time unit = 6 pi / F0",
           git=", ".join(sorted({r["git"] for r in runs})),
           machine=dict(cpu=cpu, cores=os.cpu_count(), note="wall_seconds per run: 1 thread, two runs at a time"),
           thesis_time_unit=t_unit, bond_gap=args.gap, model=main_model, t_common=float(t_end), checks=checks,
           model_comparison=comparison, runs=runs)
json.dump(out, open(jpath, "w"), indent=1)

print(f"runs: {len(runs)}; common time span {t_end:.2f} ({t_end / t_unit:.2f} thesis units)")
print("\n| model | N | phi | runs | phi actual | N_c/N at t = %.1f (range) | N_c,2/N | largest | mean dt | wall s per run |" % t_end)
print("|---|---|---|---|---|---|---|---|---|---|")
for k in sorted(groups, key=lambda k: (models.index(k[0]), k[1], k[2])):
    rs = groups[k]
    mu, lo, hi = gm[k]["nc"]
    print(f"| {k[0]} | {k[1]} | {k[2]:g} | {len(rs)} | {np.mean([r['phi_actual'] for r in rs]):.4f} "
          f"| {mu[-1]:.3f} ({lo[-1]:.3f}..{hi[-1]:.3f}) | {gm[k]['n2'][0][-1]:.3f} "
          f"| {np.mean([np.interp(t_end, r['t'], r['largest']) for r in rs]):.1f} "
          f"| {np.mean([r['t'][-1] / r['steps'] for r in rs]):.4f} | {np.mean([r['wall_seconds'] for r in rs]):.0f} |")
for c in comparison:
    print(f"{c['model']} vs {main_model} (N = {c['N']}, phi = {c['phi']:g}, {c['run']}) at t = {c['t']:.2f}: "
          + ", ".join(f"{k} {v['model']:.3f} vs {v['twin']:.3f}" for k, v in c["at_t"].items())
          + f"; aggregated fraction ratio {c['aggregated_fraction_ratio']:.3f}; wall s per unit time "
          f"{c['wall_seconds_per_unit_time']:.1f} vs {c['twin_wall_seconds_per_unit_time']:.1f}")
ok = True
for model, cs in checks.items():
    for name, c in cs.items():
        ok = ok and c["ok"]
        print(f"{model}: {name}: {'holds' if c['ok'] else 'FAILS'}")
print(json.dumps(checks, indent=1))
if args.check and not ok:
    sys.exit(1)
