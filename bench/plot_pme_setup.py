#!/usr/bin/env python3
"""Chart and tables of bench_pme_setup (bench/results/pme_setup.json): PME set-up against product.

Panel (a) per case: measured set-up and product time against the ordered real-space entries per
particle (the neighbour sweep), with the cost model's estimates dashed. Panel (b): time per
configuration with 1 and with 20 products, for the parameters chosen by pricing the product alone
(products_per_update 0) and by pricing the set-up too (1 or 20). Also prints the least-squares fit
of set-up = N (c0 + c_w P) + c_e(m) entries, the form of the cost model's set-up constants
(ewald/pme_parameters.cpp), and the achieved error of each choice.

    python3 bench/plot_pme_setup.py [--json bench/results/pme_setup.json] [--out bench/results/pme_setup.png]
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

MOMENTS = {3: "F", 6: "FT", 11: "FTS"}


def fit_constants(A, b, dofs):
    """Least-squares set-up constants (see the module docstring); prints them."""
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    # Refit without the rows the form does not describe (residual > 30 %: cutoffs close to half the
    # box, where the cell pre-test is off and every candidate takes the exact minimum image).
    keep = np.abs(A @ coef - b) / b <= 0.3
    coef, *_ = np.linalg.lstsq(A[keep], b[keep], rcond=None)
    rel = np.abs(A[keep] @ coef - b[keep]) / b[keep]
    print("set-up fit over %d of %d rows: c0 = %.2f us, c_w = %.3f us per support point, c_e = %s ns per entry;"
          " residual median %.0f %%, max %.0f %%" % (
              keep.sum(), len(b), coef[0] * 1e6, coef[1] * 1e6,
              ", ".join("%s %.1f" % (MOMENTS[d], coef[2 + i] * 1e9) for i, d in enumerate(dofs)),
              100 * np.median(rel), 100 * rel.max()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", default="bench/results/pme_setup.json")
    ap.add_argument("--out", default="bench/results/pme_setup.png")
    args = ap.parse_args()
    data = json.load(open(args.json))
    rows = data["rows"]
    sweep = [r for r in rows if r["params"]["kind"] == 0]
    choice = [r for r in rows if r["params"]["kind"] == 1]
    cases = sorted({int(r["params"]["case"]) for r in rows})

    def label(c):
        p = next(r["params"] for r in rows if int(r["params"]["case"]) == c)
        return "N=%d phi=%g %s tol %g" % (p["N"], p["phi"], MOMENTS[int(p["dof"])], p["tol"])

    # Fit of the set-up constants: setup / N = c0 + c_w P + c_e(dof) entries_per_particle.
    dofs = sorted({int(r["params"]["dof"]) for r in sweep})
    A, b = [], []
    for r in sweep:
        p = r["params"]
        row = [1.0, p["support"]] + [p["entries_per_particle"] if int(p["dof"]) == d else 0.0 for d in dofs]
        A.append(row)
        b.append(r["phases"]["setup"] / p["N"])
    supports = len({r["params"]["support"] for r in sweep})
    if len(dofs) >= 2 and supports >= 3:
        fit_constants(np.array(A), np.array(b), dofs)
    else:  # the quick run (one moment level) cannot separate the constants
        print("set-up fit skipped: %d moment level(s), %d support values (the full run fits the constants)"
              % (len(dofs), supports))
    ratio = [r["phases"]["est_setup"] / r["phases"]["setup"] for r in sweep]
    print("cost model set-up / measured: %.2f - %.2f (median %.2f)" % (min(ratio), max(ratio), np.median(ratio)))

    print("\n| case | priced | grid | P | entries/N | set-up [ms] | product [ms] | 1 product [ms] | 20 products [ms] | error/tol |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c in cases:
        for r in sorted((r for r in choice if int(r["params"]["case"]) == c), key=lambda r: r["params"]["ppu"]):
            p, ph = r["params"], r["phases"]
            priced = "product only" if p["ppu"] == 0 else "set-up / %d" % p["ppu"]
            print("| %s | %s | %d | %d | %.0f | %.3g | %.3g | %.3g | %.3g | %.2f |" % (
                label(c), priced, p["grid"], p["support"], p["entries_per_particle"], 1e3 * ph["setup"],
                1e3 * ph["product"], 1e3 * (ph["setup"] + ph["product"]), 1e3 * (ph["setup"] + 20 * ph["product"]),
                p["error"] / p["tol"]))

    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    ax = axes[0]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, c in enumerate(cases):
        rs = sorted((r for r in sweep if int(r["params"]["case"]) == c), key=lambda r: r["params"]["entries_per_particle"])
        if not rs:
            continue
        e = [r["params"]["entries_per_particle"] for r in rs]
        n = rs[0]["params"]["N"]
        col = colours[i % len(colours)]
        ax.plot(e, [r["phases"]["setup"] / n * 1e6 for r in rs], "o-", color=col, label=label(c) + ": set-up")
        ax.plot(e, [r["phases"]["product"] / n * 1e6 for r in rs], "s:", color=col, label="product")
        ax.plot(e, [r["phases"]["est_setup"] / n * 1e6 for r in rs], "--", color=col, alpha=0.5, lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("ordered real-space entries per particle")
    ax.set_ylabel("time per particle [us], one thread")
    ax.set_title("(a) set-up (o) and product (s) against the real-space range\n(dashed: the cost model's set-up)")
    ax.legend(fontsize=6, ncol=2)

    ax = axes[1]
    labels, t1_old, t1_new, t20_old, t20_new = [], [], [], [], []
    for c in cases:
        rc = {r["params"]["ppu"]: r["phases"] for r in choice if int(r["params"]["case"]) == c}
        if not all(k in rc for k in (0.0, 1.0, 20.0)):
            continue
        labels.append(label(c).replace(" phi", "\nphi").replace(" tol", "\ntol"))
        t1_old.append(rc[0.0]["setup"] + rc[0.0]["product"])
        t1_new.append(rc[1.0]["setup"] + rc[1.0]["product"])
        t20_old.append(rc[0.0]["setup"] + 20 * rc[0.0]["product"])
        t20_new.append(rc[20.0]["setup"] + 20 * rc[20.0]["product"])
    x = np.arange(len(labels))
    w = 0.2
    ax.bar(x - 1.5 * w, np.array(t1_old) / np.array(t1_old), w, label="1 product: product priced alone")
    ax.bar(x - 0.5 * w, np.array(t1_new) / np.array(t1_old), w, label="1 product: set-up priced")
    ax.bar(x + 0.5 * w, np.array(t20_old) / np.array(t20_old), w, label="20 products: product priced alone")
    ax.bar(x + 1.5 * w, np.array(t20_new) / np.array(t20_old), w, label="20 products: set-up priced / 20")
    for xi, a, b in zip(x, t1_new, t1_old):
        ax.text(xi - 0.5 * w, a / b + 0.02, "%.2f" % (a / b), ha="center", fontsize=7)
    for xi, a, b in zip(x, t20_new, t20_old):
        ax.text(xi + 1.5 * w, a / b + 0.02, "%.2f" % (a / b), ha="center", fontsize=7)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, fontsize=7)
    ax.set_ylabel("time per configuration / product-priced choice")
    ax.set_ylim(0, 1.3)
    ax.set_title("(b) pricing the set-up: time per configuration (set-up + products)")
    ax.legend(fontsize=7, loc="upper right")
    m = data.get("machine", {})
    fig.suptitle("PME set-up against product (%s, git %s)" % (m.get("cpu", ""), m.get("git", "")[:10]), fontsize=9)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print("\nwrote", args.out)


if __name__ == "__main__":
    main()
