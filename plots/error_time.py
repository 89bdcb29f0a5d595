#!/usr/bin/env python3
"""Error against wall time, one line per run (solver): the Pareto view.

usage: python3 plots/error_time.py RESULTS.h5 [-o OUT.png] [--frame F] [--substep S] [--all]
                                   [--absolute]

Left: the relative position error ||x - x_ref||_M / ||x_ref - x~||_M (dataset position_error,
written by `run --reference` or `reference = true` in a sweep spec); right: each run's own stop
measure, relative (the dual residual; ‖∇E‖ under Newton, vbd and avbd: xbruns.own_key), or with
--absolute the dual residual. Both against wall time in seconds. By default one
substep (frame 0, substep 0), whose clock starts at 0; --all concatenates every substep with a
running clock. Runs without a reference get only the residual panel. Writes OUT (PNG) and a PDF.
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

ERROR_FLOOR = 1e-16  # zeros (exact agreement) are drawn here


def reference_floor(run, a):
    """(the finest position error the reference of the plotted substep can judge, why the curve is
    not to be trusted at all or ""): its certified threshold; with --all the worst of them."""
    d = run["data"]
    if a.all:
        th = np.asarray(d.get("reference/certified_threshold", [math.inf]), dtype=float)
        ok = all(xbruns.reference_verdict(run, i)[0] for i in range(len(th)))
        return (float(np.max(th)) if len(th) else math.inf), ("" if ok else "reference unconverged")
    i = xbruns.substep_index(run, a.frame, a.substep)
    if i is None:
        return math.inf, "no reference"
    ok, why = xbruns.reference_verdict(run, i)
    th = d.get("reference/certified_threshold")
    floor = float(th[i]) if th is not None and len(th) > i else math.inf
    return floor, ("" if ok else "reference unconverged") or ("" if math.isfinite(floor) else "reference not certified")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None, help="output PNG (default: beside RESULTS)")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--substep", type=int, default=0)
    ap.add_argument("--all", action="store_true", help="every substep, with a running clock")
    ap.add_argument("--absolute", action="store_true", help="absolute dual residual instead of relative")
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    runs = xbruns.load(a.results, datasets=("frame", "substep", "iteration", "dual_residual",
                                            "relative_dual_residual", "authors_relative_dual_residual",
                                            "relative_newton_residual", "wall_time", "position_error")
                       + xbruns.REFERENCE_DATASETS)
    runs = [r for r in runs if "dual_residual" in r["data"] and len(r["data"]["dual_residual"])]
    if not runs:
        sys.exit(f"{a.results}: no simulation runs with residuals")
    have_err = any("position_error" in r["data"] for r in runs)
    ncol = 2 if have_err else 1
    fig, axes = plt.subplots(1, ncol, figsize=(6.2 * ncol, 4.4), squeeze=False)
    axes = axes[0]
    ax_err, ax_res = (axes[0], axes[1]) if have_err else (None, axes[0])
    # A label per run: the solver, plus what was swept when several runs share a solver.
    solvers = [r["attrs"].get("solver") for r in runs]
    many = len(set(solvers)) < len(solvers)
    for r in runs:
        if a.all:
            m = np.ones(len(r["data"]["iteration"]), dtype=bool)
            t = xbruns.cumulative_time(r)
        else:
            m = xbruns.substep_mask(r, a.frame, a.substep)
            t = np.asarray(r["data"]["wall_time"], dtype=float)
        if not m.any():
            continue
        lab = xbruns.label(r) if many else str(r["attrs"].get("solver"))
        status = r["attrs"].get("status", "")
        if status not in ("ok", "max_iterations"):
            lab += f" [{status}]"
        judge = reference_floor(r, a) if "position_error" in r["data"] else None
        res = np.asarray(r["data"]["dual_residual" if a.absolute else xbruns.own_key(r)])[m]
        line, = ax_res.loglog(np.maximum(t[m], 1e-6), np.maximum(res, ERROR_FLOOR), label=lab, lw=1.6)
        if ax_err is not None and "position_error" in r["data"]:
            e = np.asarray(r["data"]["position_error"])[m]
            # An exact match (the reference method itself) is drawn at the floor, not at 1e-300.
            floor, why = judge
            ax_err.loglog(np.maximum(t[m], 1e-6), np.maximum(e, ERROR_FLOOR), color=line.get_color(),
                          label=lab + (f" [{why}]" if why else ""), lw=1.6, ls="-" if not why else ":")
            # Below the finest error the reference can judge (100 × its own error estimate) the
            # curve says nothing: the dashed line marks it.
            if math.isfinite(floor):
                ax_err.axhline(max(floor, ERROR_FLOOR), color=line.get_color(), lw=0.8, ls="--")
    ax_res.set_xlabel("wall time (s)")
    ax_res.set_ylabel("dual residual" if a.absolute else "relative stop measure (dual residual, or |grad E|)")
    ax_res.grid(True, which="both", alpha=0.3)
    if ax_err is not None:
        ax_err.set_xlabel("wall time (s)")
        ax_err.set_ylabel(r"position error $\|x-x_{ref}\|_M / \|x_{ref}-\tilde x\|_M$ (0 drawn at 1e-16)")
        ax_err.grid(True, which="both", alpha=0.3)
        ax_err.legend(fontsize=8)
    else:
        ax_res.legend(fontsize=8)
    scene = runs[0]["attrs"].get("scene", "")
    where = "all substeps" if a.all else f"frame {a.frame}, substep {a.substep}"
    fig.suptitle(a.title or f"{scene}: error against wall time ({where})")
    fig.tight_layout()
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "error_time"))


if __name__ == "__main__":
    main()
