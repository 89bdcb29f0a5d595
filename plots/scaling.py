#!/usr/bin/env python3
"""Time per outer iteration against problem size, with a linear fit and R², per solver.

usage: python3 plots/scaling.py RESULTS.h5 [-o OUT.png] [--size rows|particles|nonzeros|tets]
                                [--loglog]

Time per outer iteration = wall_time / outer_iterations of each run (ms); size = the run's
attribute (rows = constraints = rows of A; for tet scenes that is the number of tets). Repeats
at one size are summarised by their median. The fit t = a·size + b is least squares on the
medians; a, b and R² are printed and shown in the legend. Writes PNG and PDF.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import xbruns  # noqa: E402


def per_iteration(runs, size_key):
    """{solver: (sizes, ms per outer iteration)} from runs that did at least one iteration."""
    pts = {}
    for r in runs:
        at = r["attrs"]
        n = xbruns.as_number(at.get("rows" if size_key == "tets" else size_key))
        its = xbruns.as_number(at.get("outer_iterations"))
        wt = xbruns.as_number(at.get("wall_time"))
        if n is None or not its or wt is None or at.get("status") in ("error", "nan", "breakdown"):
            continue
        pts.setdefault(at.get("solver", "?"), {}).setdefault(n, []).append(1e3 * wt / its)
    out = {}
    for s, d in pts.items():
        sizes = sorted(d)
        out[s] = (np.array(sizes), np.array([float(np.median(d[n])) for n in sizes]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None)
    ap.add_argument("--size", default="rows", help="size attribute: rows (= tets for tet scenes), particles, nonzeros")
    ap.add_argument("--loglog", action="store_true")
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    runs = xbruns.load(a.results, datasets=())
    data = per_iteration(runs, a.size)
    if not data:
        sys.exit(f"{a.results}: no runs with outer iterations and a '{a.size}' attribute")
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for s, (n, t) in sorted(data.items()):
        pts, = ax.plot(n, t, "o", label=s)
        if len(n) >= 2:
            k, b, r2 = xbruns.linear_fit(n, t)
            xx = np.linspace(n.min(), n.max(), 100)
            ax.plot(xx, k * xx + b, "-", color=pts.get_color(), alpha=0.7,
                    label=f"{s} fit: {k * 1e3:.3g} ms/1K + {b:.3g} ms, R²={r2:.4f}")
            print(f"{s}\tsizes={len(n)}\tslope_ms_per_1k={k * 1e3:.6g}\tintercept_ms={b:.6g}\tR2={r2:.6f}")
    if a.loglog:
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel({"rows": "constraints (rows of A; tets for tet scenes)", "tets": "tets"}.get(a.size, a.size))
    ax.set_ylabel("time per outer iteration (ms)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    scene = runs[0]["attrs"].get("scene", "") if runs else ""
    ax.set_title(a.title or f"{scene}: time per outer iteration against size")
    fig.tight_layout()
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "scaling"))


if __name__ == "__main__":
    main()
