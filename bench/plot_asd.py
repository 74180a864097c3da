#!/usr/bin/python3
"""Chart the accelerated-SD benchmark (bench_asd): (a) time per FTS solve against N in periodic boxes
for phi = 0.1, 0.3, 0.45 on 1 and 2 threads with the fitted exponent, and the dense solver beside
it; (b) the phases of the 2-thread solves (far-field set-up, near-field assembly, factorisation,
Krylov); (c) far-field products per solve against N; (d) dense vs accelerated at small N (the
`solver = "auto"` crossover). Prints the fitted exponents and the 2-thread speed-ups.

usage: plot_asd.py [RESULTS.json] [OUT.png] [MORE.json ...]   (default: bench/results/asd.json; MORE:
rows of further runs, e.g. bench_asd with BENCH_MIN_N=100000 -> asd_from_100000.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/asd.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
extra_git = []
for extra in sys.argv[3:]:
    e = json.load(open(extra))
    rows += e["rows"]
    extra_git.append(e.get("machine", {}).get("git", "?"))
PHIS = [0.1, 0.3, 0.45]
COLORS = {0.1: "tab:blue", 0.3: "tab:orange", 0.45: "tab:red"}


def sel(section, **kw):
    res = []
    for r in rows:
        p = r["params"]
        if p.get("section") != section:
            continue
        if all(abs(p.get(k, -1) - v) < 1e-9 for k, v in kw.items()):
            res.append(r)
    return sorted(res, key=lambda r: r["params"]["N"])


threads = sorted({r["params"]["threads"] for r in rows if r["params"].get("section") == 1})
tmax = max(threads)
fig, ax = plt.subplots(2, 2, figsize=(13, 10))

a = ax[0][0]
for phi in PHIS:
    for t in threads:
        rs = sel(1, phi=phi, threads=t, dense=0)
        if not rs:
            continue
        n = np.array([r["params"]["N"] for r in rs])
        y = np.array([r["phases"]["total"] for r in rs])
        label = f"phi={phi}, {int(t)} thread(s)"
        if len(n) >= 2:
            k = np.polyfit(np.log(n), np.log(y), 1)[0]
            label += f", N^{k:.2f}"
            print(f"phi {phi} threads {int(t)}: exponent {k:.2f} from N = {int(n[0])} to {int(n[-1])}")
        a.loglog(n, y, "o-" if t == tmax else "s--", color=COLORS[phi], label=label, alpha=1.0 if t == tmax else 0.5)
    d = sel(1, phi=phi, threads=tmax, dense=1)
    if d:
        a.loglog([r["params"]["N"] for r in d], [r["phases"]["total"] for r in d], "x:", color=COLORS[phi],
                 label=f"dense SD, phi={phi}")
a.set_xlabel("N")
a.set_ylabel("seconds per deterministic FTS solve (prepare + solve)")
a.set_title("accelerated SD, periodic PME, tolerance 1e-4")
a.legend(fontsize=7)
a.grid(True, which="both", alpha=0.3)

a = ax[0][1]
PH = ["far_field_setup", "near_field_assembly", "factorisation", "krylov"]
labels, bottoms = [], None
bars = {p: [] for p in PH}
for phi in PHIS:
    for r in sel(1, phi=phi, threads=tmax, dense=0):
        labels.append(f"{phi}\n{int(r['params']['N'])}")
        for p in PH:
            bars[p].append(r["phases"][p])
x = np.arange(len(labels))
total = sum(np.array(bars[p]) for p in PH)
bottom = np.zeros(len(labels))
for p in PH:
    frac = np.array(bars[p]) / total
    a.bar(x, frac, bottom=bottom, label=p)
    bottom += frac
for i, t in enumerate(total):
    a.text(x[i], 1.01, f"{t:.3g}", ha="center", va="bottom", fontsize=5, rotation=90)
a.set_xticks(x)
a.set_xticklabels(labels, fontsize=6)
a.set_ylim(0, 1.15)
a.set_ylabel(f"share of the solve ({int(tmax)} threads); total seconds on top")
a.set_title("phases per solve (phi / N)")
a.legend(fontsize=7, loc="lower left")

a = ax[1][0]
for phi in PHIS:
    rs = sel(1, phi=phi, threads=tmax, dense=0)
    if rs:
        a.semilogx([r["params"]["N"] for r in rs], [r["phases"]["products"] for r in rs], "o-", color=COLORS[phi],
                   label=f"phi={phi}")
a.axhline(15, color="gray", ls=":", label="goal: 15 products")
a.set_xlabel("N")
a.set_ylabel("far-field products per solve")
a.set_title("GMRES iterations + 1 (tolerance 1e-4, Krylov residual 2e-6)")
a.legend(fontsize=7)
a.grid(True, alpha=0.3)

a = ax[1][1]
for per, name in [(0, "open (direct far field)"), (1, "periodic (PME / dense Ewald)")]:
    rs = sel(2, periodic=per)
    if rs:
        n = [r["params"]["N"] for r in rs]
        a.loglog(n, [r["phases"]["accelerated"] for r in rs], "o-", label=f"accelerated, {name}")
        a.loglog(n, [r["phases"]["dense"] for r in rs], "x--", label=f"dense, {name}")
a.set_xlabel("N")
a.set_ylabel("seconds per FTS solve, phi = 0.3")
a.set_title("solver = \"auto\" crossover")
a.legend(fontsize=7)
a.grid(True, which="both", alpha=0.3)

for phi in PHIS:
    one = {r["params"]["N"]: r["phases"]["total"] for r in sel(1, phi=phi, threads=1, dense=0)}
    two = {r["params"]["N"]: r["phases"]["total"] for r in sel(1, phi=phi, threads=tmax, dense=0)}
    for n in sorted(set(one) & set(two)):
        if tmax > 1:
            print(f"phi {phi} N {int(n)}: {int(tmax)} threads / 1 thread speed-up {one[n] / two[n]:.2f}")
m = data.get("machine", {})
more = f" (+ rows from git {', '.join(extra_git)})" if extra_git else ""
fig.suptitle(f"bench_asd on {m.get('cpu', '?')} ({m.get('logical_cores', '?')} cores), {m.get('date', '')}, git {m.get('git', '')}{more}",
             fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
