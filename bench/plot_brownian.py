#!/usr/bin/python3
"""Chart the Brownian SD step benchmark (bench_brownian, issue 13): (a) shares of one Fixman step,
set-up, far-field noise (Lanczos), near-field noise, solve at x0 and drift (midpoint prepare +
solve), one bar per (N, threads), with the step's wall and CPU seconds, the engine's measured
step and the load average written above; (b) far-field products per step (Lanczos
iterations, GMRES products of the x0 solve and of the midpoint solve) against the goal of 30.
Prints the table of docs/benchmarks.md and the goals.

usage: plot_brownian.py [RESULTS.json] [OUT.png] [MORE.json ...]   (default: bench/results/brownian.json;
MORE: rows of further runs, e.g. BENCH_MIN_N=10000 BENCH_THREADS=2 -> one more row each)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/brownian.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
for extra in sys.argv[3:]:
    rows += json.load(open(extra))["rows"]
rows = sorted(rows, key=lambda r: (r["params"]["N"], r["params"]["threads"]))
tol = rows[0]["params"]["tolerance"]

PARTS = [("setup", "set-up (far field, near field, factor)", "tab:gray"),
         ("far_noise", "far-field noise (Lanczos)", "tab:blue"),
         ("near_noise", "near-field noise", "tab:cyan"),
         ("solve", "solve at x0 (F + xi)", "tab:green"),
         ("drift", "drift (midpoint prepare + solve)", "tab:red")]
PRODUCTS = [("lanczos_iterations", "Lanczos", "tab:blue"),
            ("products_solve", "solve at x0", "tab:green"),
            ("products_drift", "midpoint solve", "tab:red")]

labels = [f"N={int(r['params']['N'])}\n{int(r['params']['threads'])} thr" for r in rows]
x = np.arange(len(rows))
fig, ax = plt.subplots(1, 2, figsize=(14, 5.5))

a = ax[0]
# Shares of the step (a log scale would hide all but the lowest part), the total on top.
total = np.array([sum(r["phases"][k] for k, _, _ in PARTS) for r in rows])
bottom = np.zeros(len(rows))
for key, name, color in PARTS:
    y = np.array([r["phases"][key] for r in rows]) / total
    a.bar(x, y, bottom=bottom, color=color, label=name, width=0.6)
    bottom += y
for i, r in enumerate(rows):
    f = r["phases"]
    text = f"{total[i]:.3g} s\n(CPU {f.get('cpu_step', 0):.3g} s)"
    if f["engine_step"] > 0:
        text += f"\nengine {f['engine_step']:.3g} s"
    text += f"\nload {f.get('load_average', -1):.1f}"
    a.text(x[i], 1.02, text, ha="center", va="bottom", fontsize=7)
a.set_ylim(0, 1.45)
a.set_xticks(x)
a.set_xticklabels(labels)
a.set_ylabel("share of the Brownian step (wall time)")
a.set_title(f"Brownian SD step (Fixman), phi = 0.4, sheared periodic, FTS, tol {tol:g}", fontsize=10)
a.legend(fontsize=7, loc="upper left", ncol=2)

a = ax[1]
bottom = np.zeros(len(rows))
for key, name, color in PRODUCTS:
    y = np.array([r["phases"][key] for r in rows])
    a.bar(x, y, bottom=bottom, color=color, label=name, width=0.6)
    bottom += y
a.axhline(30, color="k", ls=":", lw=1, label="goal: 30 products per step")
a.set_xticks(x)
a.set_xticklabels(labels)
a.set_ylabel("far-field products per Brownian step")
a.set_title("far-field products per step")
a.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")

print(f"| N | threads | step [s] | set-up | far noise | near noise | solve at x0 | drift | engine step | "
      f"run-loop start solve | products (Lanczos + x0 + midpoint) | CPU s: step / engine step | load |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    p, f = r["params"], r["phases"]
    print(f"| {int(p['N'])} | {int(p['threads'])} | {f['step']:.3g} | {f['setup']:.3g} | {f['far_noise']:.3g} | "
          f"{f['near_noise']:.3g} | {f['solve']:.3g} | {f['drift']:.3g} | {f['engine_step']:.3g} | "
          f"{f['start_solve']:.3g} | {f['products_step']:.0f} ({f['lanczos_iterations']:.0f} + "
          f"{f['products_solve']:.0f} + {f['products_drift']:.0f}) | {f.get('cpu_step', 0):.3g} / "
          f"{f.get('cpu_engine_step', 0):.3g} | {f.get('load_average', -1):.1f} |")
for r in rows:
    p, f = r["params"], r["phases"]
    if int(p["N"]) == 10000 and int(p["threads"]) == 2:
        print(f"goal 1 s per step at N = 1e4 on 2 threads: {f['step']:.2f} s (engine {f['engine_step']:.2f} s): "
              f"{'met' if f['engine_step'] <= 1.0 else 'not met'}")
worst = max(r["phases"]["products_step"] for r in rows)
print(f"goal <= 30 far-field products per step: at most {worst:.0f}: {'met' if worst <= 30 else 'not met'}")
