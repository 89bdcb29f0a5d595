#!/usr/bin/env python3
"""A metric against one or two swept parameters, per solver.

usage: python3 plots/sweep.py RESULTS.h5 [-o OUT.png] [--metric M] [--x KEY] [--y KEY]
                              [--tol T] [--frame F] [--substep S]

metrics: outer_iterations (attribute, all substeps), iterations_to_tolerance and
time_to_tolerance (first outer iteration / wall time of one substep at which the run's own relative
stop measure <= --tol, default the run's rtol: the dual residual, ‖∇E‖ under Newton, vbd and avbd), final_dual_residual, relative_dual_residual,
wall_time, status, or any other numeric run attribute. --x/--y default to the run's swept keys
(attribute sweep_params). With one key: one line per solver; with two: one heat map per solver.
Repeats of a point are summarised by their median (status: the worst). Writes PNG and PDF.
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import xbruns  # noqa: E402

LOG_METRICS = {"final_dual_residual", "relative_dual_residual", "time_to_tolerance", "wall_time"}


def metric_value(run, metric, tol, frame, substep):
    a = run["attrs"]
    if metric == "status":
        return a.get("status", "error")
    if metric in ("iterations_to_tolerance", "time_to_tolerance"):
        t = tol if tol is not None else float(a.get("rtol", 1e-6))
        it, sec = xbruns.to_tolerance(run, t, frame, substep, metric="own")
        return it if metric == "iterations_to_tolerance" else sec
    v = xbruns.as_number(a.get(metric))
    return math.nan if v is None else v


def sort_key(v):
    n = xbruns.as_number(v)
    return (0, n, "") if n is not None else (1, 0, str(v))


def summarise(values, metric):
    if metric == "status":
        return max(values, key=lambda s: xbruns.STATUS_ORDER.index(s) if s in xbruns.STATUS_ORDER else 99)
    vals = [v for v in values if not math.isnan(v)]
    return float(np.median(vals)) if vals else math.nan


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None)
    ap.add_argument("--metric", default="outer_iterations")
    ap.add_argument("--x", default=None, help="swept key on the x axis (default: the first swept key)")
    ap.add_argument("--y", default=None, help="second key (default: the second swept key, if any)")
    ap.add_argument("--tol", type=float, default=None, help="relative dual residual for *_to_tolerance")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--substep", type=int, default=0)
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    runs = xbruns.load(a.results)
    if not runs:
        sys.exit(f"{a.results}: no simulation runs")
    keys = list(xbruns.swept(runs[0]))
    xkey = a.x or (keys[0] if keys else None)
    ykey = a.y or (keys[1] if len(keys) > 1 and keys[1] != xkey else None)
    if xkey is None:
        sys.exit(f"{a.results}: no swept keys (attribute sweep_params); name one with --x")
    for k in [xkey] + ([ykey] if ykey else []):
        if not any(k in r["attrs"] for r in runs):
            sys.exit(f"{a.results}: no run has the attribute '{k}'")

    # (solver, x, y) → metric over repeats
    cells = {}
    for r in runs:
        s = r["attrs"].get("solver", "?")
        key = (s, r["attrs"].get(xkey), r["attrs"].get(ykey) if ykey else None)
        cells.setdefault(key, []).append(metric_value(r, a.metric, a.tol, a.frame, a.substep))
    table = {k: summarise(v, a.metric) for k, v in cells.items()}
    solvers = sorted({k[0] for k in table})
    xs = sorted({k[1] for k in table}, key=sort_key)
    ys = sorted({k[2] for k in table}, key=sort_key) if ykey else [None]
    ylabel = a.metric.replace("_", " ") + (" (s)" if a.metric in ("time_to_tolerance", "wall_time") else "")
    numeric_x = all(xbruns.as_number(x) is not None for x in xs)

    if ykey is None and a.metric != "status":
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        for s in solvers:
            pts = [(x, table.get((s, x, None), math.nan)) for x in xs]
            if numeric_x:
                ax.plot([float(x) for x, _ in pts], [v for _, v in pts], "o-", label=s, lw=1.6)
            else:
                ax.plot(range(len(pts)), [v for _, v in pts], "o-", label=s, lw=1.6)
        if not numeric_x:
            ax.set_xticks(range(len(xs)), [str(x) for x in xs])
        else:
            nx = [float(x) for x in xs if float(x) > 0]
            if len(nx) == len(xs) and len(nx) > 1 and max(nx) / min(nx) > 100:
                ax.set_xscale("log")
        if a.metric in LOG_METRICS:
            ax.set_yscale("log")
        ax.set_xlabel(xkey)
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    else:
        # Heat maps: one per solver, rows = y values (or one row), columns = x values.
        fig, axes = plt.subplots(1, len(solvers), figsize=(1.2 + 0.9 * len(xs) * len(solvers) + 1.5 * len(solvers),
                                                          1.4 + 0.5 * len(ys)), squeeze=False)
        for ax, s in zip(axes[0], solvers):
            grid = [[table.get((s, x, y)) for x in xs] for y in ys]
            if a.metric == "status":
                colours = [[matplotlib.colors.to_rgb(xbruns.STATUS_COLOURS.get(v, "#ffffff") if v else "#ffffff")
                            for v in row] for row in grid]
                ax.imshow(colours, aspect="auto")
                for i, row in enumerate(grid):
                    for j, v in enumerate(row):
                        ax.text(j, i, v or "-", ha="center", va="center", fontsize=7)
            else:
                arr = np.array([[math.nan if v is None else v for v in row] for row in grid], dtype=float)
                shown = np.log10(arr) if a.metric in LOG_METRICS else arr
                im = ax.imshow(shown, aspect="auto", cmap="viridis")
                fig.colorbar(im, ax=ax, label=("log10 " if a.metric in LOG_METRICS else "") + ylabel)
                for i in range(arr.shape[0]):
                    for j in range(arr.shape[1]):
                        if not math.isnan(arr[i, j]):
                            ax.text(j, i, f"{arr[i, j]:.3g}", ha="center", va="center", fontsize=7, color="w")
            ax.set_xticks(range(len(xs)), [xbruns.fmt(x) for x in xs], rotation=45)
            ax.set_yticks(range(len(ys)), [xbruns.fmt(y) for y in ys] if ykey else [""])
            ax.set_xlabel(xkey)
            if ykey:
                ax.set_ylabel(ykey)
            ax.set_title(s)
    scene = runs[0]["attrs"].get("scene", "")
    fig.suptitle(a.title or f"{scene}: {a.metric.replace('_', ' ')}")
    fig.tight_layout()
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "sweep_" + a.metric))
    # The numbers, for the record.
    for k in sorted(table, key=lambda k: (k[0], sort_key(k[1]), sort_key(k[2]))):
        print(f"{k[0]}\t{xkey}={xbruns.fmt(k[1])}" + (f"\t{ykey}={xbruns.fmt(k[2])}" if ykey else "") +
              f"\t{a.metric}={xbruns.fmt(table[k])}")


if __name__ == "__main__":
    main()
