#!/usr/bin/python3
"""Fast spreading/interpolation kernels against the previous loops (issue 12): the same bench_pme
rows (kind 0) of two builds run one after the other on one machine, as new/old ratios of the wave
part and of the whole product, per tolerance, for N = 1e4 and 1e5, F and FTS, phi 0.1 and 0.4,
1 and 2 threads. Prints the table of docs/benchmarks.md.

usage: plot_pme_kernels.py [--old OLD.json ...] [--new NEW.json ...] [--out PNG]
defaults: bench/results/pme_kernels_before.json, bench/results/pme_kernels.json,
          bench/results/pme_kernels.png
"""
import argparse
import json
import math
import statistics

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

ap = argparse.ArgumentParser()
ap.add_argument("--old", nargs="+", default=["bench/results/pme_kernels_before.json"])
ap.add_argument("--new", nargs="+", default=["bench/results/pme_kernels.json"])
ap.add_argument("--out", default="bench/results/pme_kernels.png")
args = ap.parse_args()


def rows(files):
    out = {}
    for f in files:
        for r in json.load(open(f))["rows"]:
            p = r["params"]
            if p.get("kind") != 0:
                continue
            key = (p["N"], p["dof"], p["phi"], p["tol"], p["threads"])
            out.setdefault(key, []).append((r["phases"], p))
    return out


old, new = rows(args.old), rows(args.new)
keys = sorted(set(old) & set(new))


def med(lst, phase):
    return statistics.median(x[0][phase] for x in lst)


print("| N | moments | φ | tol | grid, P | threads | wave old → new [s] | product old → new [s] | new/old wave | new/old product |")
print("|---|---|---|---|---|---|---|---|---|---|")
for k in keys:
    n, dof, phi, tol, thr = k
    p = new[k][0][1]
    assert (p["grid"], p["support"]) == (old[k][0][1]["grid"], old[k][0][1]["support"]), k
    wo, wn, po, pn = med(old[k], "wave"), med(new[k], "wave"), med(old[k], "product"), med(new[k], "product")
    print(f"| {n} | {'F' if dof == 3 else 'FTS'} | {phi} | {tol:.0e} | {p['grid']}, {p['support']} | {thr} | "
          f"{wo:.3g} → {wn:.3g} | {po:.3g} → {pn:.3g} | {wn / wo:.2f} | {pn / po:.2f} |")
for phase in ("wave", "product"):
    for dof in (3, 11):
        r = [med(new[k], phase) / med(old[k], phase) for k in keys if k[1] == dof]
        if r:
            print(f"{phase} {'F' if dof == 3 else 'FTS'}: new/old median {statistics.median(r):.2f}, "
                  f"range {min(r):.2f}-{max(r):.2f} over {len(r)} rows")

# Exponent of the product time against N (least squares in log-log over the N present, 2 threads),
# for every series of the new build with at least 3 sizes; the old build's where it has the same.
def slope(d, ks):
    xs = [math.log(k[0]) for k in ks]
    ys = [math.log(med(d[k], "product")) for k in ks]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


print("| series (2 threads) | N | old product [s] | new product [s] | exponent old | exponent new |")
print("|---|---|---|---|---|---|")
for dof, phi, tol in sorted({(k[1], k[2], k[3]) for k in new if k[4] == 2}):
    ks = sorted((k for k in new if k[1:4] == (dof, phi, tol) and k[4] == 2), key=lambda k: k[0])
    if len(ks) < 3:
        continue
    both = all(k in old for k in ks)
    ns = ", ".join(f"{k[0]:.0e}" for k in ks)
    to = ", ".join(f"{med(old[k], 'product'):.3g}" for k in ks) if both else "–"
    tn = ", ".join(f"{med(new[k], 'product'):.3g}" for k in ks)
    so = f"{slope(old, ks):.2f}" if both else "–"
    name = "F" if dof == 3 else "FTS"
    print(f"| {name} φ {phi} tol {tol:.0e} | {ns} | {to} | {tn} | {so} | {slope(new, ks):.2f} |")

fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
styles = {(3, 0.1): ("C0", "o"), (3, 0.4): ("C0", "s"), (11, 0.1): ("C3", "o"), (11, 0.4): ("C3", "s")}
for ax, n in zip(axes, (10000, 100000)):
    for (dof, phi), (col, mk) in styles.items():
        for thr, ls in ((1, ":"), (2, "-")):
            ks = sorted((k for k in keys if k[0] == n and k[1] == dof and k[2] == phi and k[4] == thr),
                        key=lambda k: k[3])
            if not ks:
                continue
            tols = [k[3] for k in ks]
            ax.plot(tols, [med(new[k], "wave") / med(old[k], "wave") for k in ks], ls=ls, marker=mk, color=col,
                    label=f"{'F' if dof == 3 else 'FTS'} φ {phi}, {thr} thr, wave")
            ax.plot(tols, [med(new[k], "product") / med(old[k], "product") for k in ks], ls=ls, marker=mk,
                    color=col, alpha=0.35, mfc="none")
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("requested tolerance")
    ax.set_title(f"N = {n:.0e}: new / old time (solid markers: wave part; faint: whole product)")
    ax.title.set_fontsize(9)
    ax.grid(alpha=0.3)
axes[0].set_ylabel("time ratio, vectorised kernels / generic loops")
axes[0].legend(fontsize=7, ncol=2)
gits = [json.load(open(f))["machine"]["git"] for f in (args.new[0], args.old[0])]
fig.suptitle(f"PME: vectorised spreading/interpolation ({gits[0]}) against the generic loops ({gits[1]}), "
             "same machine, one run each (medians of 3-5 products)", fontsize=9)
fig.tight_layout()
fig.savefig(args.out, dpi=110)
print("wrote", args.out)
