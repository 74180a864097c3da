#!/usr/bin/python3
"""Chart the step-graph benchmark: time of one evaluation (forces, hydrodynamic set-up, output
diagnostics, solve) per scene and N, on 1 thread and on 2 threads with the phases run one after
another ("serial") or as OpenMP tasks ("tasks"), with the phase breakdown of the 2-thread runs.

usage: plot_step.py [RESULTS.json] [OUT.png]   (default: bench/results/step_graph.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

SCENES = ["dense_sd", "pme_shear", "direct_morse", "free_draining_dlvo"]
PHASES = ["forces", "hydro_setup", "diagnostics", "solve"]

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/step_graph.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
rows = json.load(open(src))["rows"]


def row(scene, n, threads, mode):
    for r in rows:
        p = r["params"]
        if p["scene"] == scene and p["N"] == n and p["threads"] == threads and p["mode"] == mode:
            return r["phases"]
    return None


labels, t1, ts, tt, parts_s, parts_t = [], [], [], [], [], []
for s_i, name in enumerate(SCENES):
    for n in sorted({r["params"]["N"] for r in rows if r["params"]["scene"] == s_i}):
        one, ser, tsk = row(s_i, n, 1, 0), row(s_i, n, 2, 0), row(s_i, n, 2, 1)
        if not (one and ser and tsk):
            continue
        labels.append(f"{name}\nN={int(n)}")
        t1.append(one["evaluation"])
        ts.append(ser["evaluation"])
        tt.append(tsk["evaluation"])
        parts_s.append([ser.get(p, 0.0) for p in PHASES])
        parts_t.append([tsk.get(p, 0.0) for p in PHASES])
        print(f"{name:19s} N={int(n):6d}: 1 thread {one['evaluation']:.3e} s; 2 threads serial "
              f"{ser['evaluation']:.3e} s, tasks {tsk['evaluation']:.3e} s; "
              f"serial/tasks {ser['evaluation'] / tsk['evaluation']:.3f}, 1/2 threads (tasks) "
              f"{one['evaluation'] / tsk['evaluation']:.2f}")

x = np.arange(len(labels))
fig, axes = plt.subplots(2, 1, figsize=(max(10, 1.1 * len(labels)), 9))
ax = axes[0]
ax.bar(x - 0.27, np.array(ts) / np.array(t1), 0.27, label="2 threads, phases serial")
ax.bar(x, np.array(tt) / np.array(t1), 0.27, label="2 threads, phases as tasks")
for i in range(len(x)):
    ax.text(x[i] + 0.27, 0.02, f"{ts[i] / tt[i]:.2f}x", ha="center", va="bottom", fontsize=8, rotation=90)
ax.axhline(1.0, color="grey", lw=0.8)
ax.axhline(0.5, color="grey", lw=0.8, ls=":")
ax.set_ylabel("evaluation time / 1 thread")
ax.set_title("One step's evaluation: 2 threads relative to 1 (numbers: serial phases / task graph)")
ax.set_xticks(x)
ax.set_xticklabels(labels, fontsize=8, rotation=30, ha="right")
ax.legend()
ax = axes[1]
ps, pt = np.array(parts_s), np.array(parts_t)
bottom_s, bottom_t = np.zeros(len(x)), np.zeros(len(x))
colors = ["C0", "C1", "C2", "C3"]
for k, p in enumerate(PHASES):
    ax.bar(x - 0.2, ps[:, k] / np.array(ts), 0.38, bottom=bottom_s, color=colors[k], label=p)
    ax.bar(x + 0.2, pt[:, k] / np.array(ts), 0.38, bottom=bottom_t, color=colors[k], alpha=0.6)
    bottom_s += ps[:, k] / np.array(ts)
    bottom_t += pt[:, k] / np.array(ts)
ax.set_ylabel("phase wall time / serial evaluation")
ax.set_title("Phases at 2 threads: left serial, right tasks (overlapping phases sum to more than the whole)")
ax.set_xticks(x)
ax.set_xticklabels(labels, fontsize=8, rotation=30, ha="right")
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
