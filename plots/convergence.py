#!/usr/bin/env python3
"""Dual residual against outer iteration and against wall time, one line per run, log scale; and
the mean linear iterations per solve of every global run (the cost of one outer iteration).

usage: python3 plots/convergence.py RESULTS.h5 [-o OUT.png] [--relative] [--frame F] [--metric true|authors]

--metric authors draws `authors_dual_residual` (the residual the MGPBD authors' code logs:
‖C(x̃) + α̃λ_k‖ for local sweeps, ‖C(x_{k−1}) + α̃λ_k‖ for global methods) instead of the true
‖C(x_k) + α̃λ_k‖; runs recorded before that dataset existed are left out with a note.

Reads the schema of results/README.md through plots/xbruns.py: every simulation run under /runs
with its datasets `iteration`, `frame`, `substep`, `dual_residual`, `relative_dual_residual`,
`wall_time` and `linear_iterations`, and its attributes `solver`, `form_used`, `status`. Substeps
are concatenated along the iteration axis; wall time is cumulative over substeps. A global
method run in both forms is drawn dashed (dual) and solid (primal). Writes OUT (PNG) and the same
figure as PDF beside it.
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

DATASETS = ("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "authors_dual_residual",
            "authors_relative_dual_residual", "wall_time", "linear_iterations")


def run_label(run):
    a = run["attrs"]
    form = a.get("form_used", "")
    return f"{a.get('solver', '?')}" + (f" {form}" if form in ("dual", "primal") else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None, help="output PNG (default: beside RESULTS)")
    ap.add_argument("--relative", action="store_true", help="plot the residual relative to each substep's first")
    ap.add_argument("--frame", type=int, default=None, help="only this frame")
    ap.add_argument("--metric", choices=xbruns.METRICS, default="true",
                    help="true: the dual residual of the state; authors: the one the authors' code logs")
    a = ap.parse_args()
    key = xbruns.residual_key(a.metric, a.relative)
    runs = xbruns.load(a.results, DATASETS)
    for r in runs:
        if "dual_residual" in r["data"] and key not in r["data"]:
            print(f"note: {r['name']} has no {key} (recorded before it existed): left out", file=sys.stderr)
    runs = [r for r in runs if key in r["data"]]
    if not runs:
        sys.exit(f"{a.results}: no simulation runs with {key} to plot")
    out = a.out or xbruns.default_out(a.results, "convergence")
    ylabel = "relative dual residual" if a.relative else r"dual residual $\|C + \tilde\alpha\lambda\|_2$"
    if a.metric == "authors":
        ylabel += " (authors' log)"
    fig, (ax1, ax2, ax3) = plt.subplots(1, 3, figsize=(15, 4.2), gridspec_kw={"width_ratios": [1, 1, 0.8]})
    bars = []
    for r in runs:
        d = r["data"]
        keep = xbruns.substep_mask(r, a.frame)
        y = np.asarray(d[key], dtype=float)[keep]
        y = np.where(y > 0, y, np.nan)
        label = f"{run_label(r)} ({r['attrs'].get('status', '?')})"
        style = "--" if r["attrs"].get("form_used") == "dual" else "-"
        ax1.semilogy(np.arange(len(y)), y, style, label=label, lw=1.6)
        ax2.loglog(np.maximum(xbruns.cumulative_time(r)[keep], 1e-6), y, style, label=label, lw=1.6)
        its = np.asarray(d.get("linear_iterations", []), dtype=float)[keep] if "linear_iterations" in d else []
        solves = its[np.asarray(d["iteration"])[keep] > 0] if len(its) else []
        if len(solves) and solves.max() > 0:
            bars.append((run_label(r), float(np.mean(solves))))
    substeps = any(len(np.unique(np.stack([r["data"]["frame"], r["data"]["substep"]]), axis=1).T) > 1 for r in runs)
    ax1.set_xlabel("outer iteration" + (" (substeps concatenated)" if substeps else ""))
    ax2.set_xlabel("wall time [s]")
    for ax in (ax1, ax2):
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)
    if bars:
        ax3.barh([b[0] for b in bars], [b[1] for b in bars], color="#5c6bc0")
        ax3.set_xscale("log")
        ax3.set_xlabel("mean linear iterations per solve")
        ax3.invert_yaxis()
        ax3.grid(True, axis="x", which="both", alpha=0.3)
        for i, (_, v) in enumerate(bars):
            ax3.text(v, i, f" {v:.0f}", va="center", fontsize=8)
    else:
        ax3.set_axis_off()
    scenes = sorted({str(r["attrs"].get("scene", "?")) for r in runs})
    what = "dual residual as the authors log it" if a.metric == "authors" else "dual residual"
    fig.suptitle(f"{', '.join(scenes)}: {what} per outer iteration")
    fig.tight_layout()
    xbruns.save(fig, out)


if __name__ == "__main__":
    main()
