#!/usr/bin/python3
"""Chart the long-run memory benchmark: resident set size (RSS) and the live C heap (mallinfo2)
against step, sampled at every checkpoint (every 1000 steps), with the RSS before the simulation
and the least-squares line over the second half of the run (its slope in bytes per step is
printed and drawn).

usage: plot_memory.py [RESULTS.json] [OUT.png]   (default: bench/results/memory.json)
"""
import json
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/memory.json"
out = sys.argv[2] if len(sys.argv) > 2 else src.replace(".json", ".png")
data = json.load(open(src))
rows = data["rows"]
samples = [r for r in rows if "step" in r["params"] and r["params"]["step"] >= 0]
before = [r for r in rows if r["params"].get("step") == -1]
summary = [r for r in rows if "summary" in r["params"]]

step = np.array([r["params"]["step"] for r in samples])
rss = np.array([r["phases"]["rss_bytes"] for r in samples]) / 2**20
heap = np.array([r["phases"].get("heap_in_use_bytes", np.nan) for r in samples]) / 2**20
half = len(step) // 2
slope, icpt = np.polyfit(step[half:], rss[half:], 1) if len(step) - half > 1 else (0.0, rss[-1])
print(f"{len(step)} samples, steps {int(step[0])} to {int(step[-1])}: RSS first {rss[0]:.2f} MB, last {rss[-1]:.2f} MB, "
      f"max {rss.max():.2f} MB; slope over the second half {slope * 2**20:.3g} bytes/step "
      f"({slope * 1e5:.3g} MB per 10^5 steps); live heap {heap[0]:.3f} -> {heap[-1]:.3f} MB")

fig, ax = plt.subplots(figsize=(9, 5))
ax.plot(step, rss, ".-", ms=3, lw=0.8, label="RSS at each checkpoint")
ax.plot(step, heap, ".-", ms=2, lw=0.8, color="tab:green", label="live C heap (mallinfo2)")
if before:
    ax.axhline(before[0]["phases"]["rss_bytes"] / 2**20, color="grey", ls=":", lw=1,
               label="RSS before the simulation is built")
ax.plot(step[half:], icpt + slope * step[half:], "r--", lw=1,
        label=f"fit over the second half: {slope * 2**20:.3g} bytes/step")
m = data.get("machine", {})
ax.set_xlabel("step")
ax.set_ylabel("resident set size [MB = 2^20 bytes]")
ax.set_ylim(0, max(rss.max(), before[0]["phases"]["rss_bytes"] / 2**20 if before else 0) * 1.15)
ax.set_title("27 Brownian spheres, free draining, frame every 100 steps, checkpoint every 1000\n"
             f"({m.get('cpu', '')}, {m.get('git', '')})", fontsize=9)
ax.legend(loc="lower right")
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")
