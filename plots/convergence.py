#!/usr/bin/env python3
"""Dual residual against outer iteration and against wall time, one line per run, log scale.

usage: python3 plots/convergence.py RESULTS.h5 [-o OUT.png] [--relative] [--frame F]

Reads the schema of results/README.md: every simulation run under /runs with its datasets
`iteration`, `frame`, `substep`, `dual_residual`, `relative_dual_residual` and `wall_time`.
Substeps are concatenated along the iteration axis; wall time is cumulative over substeps.
Writes OUT (PNG) and the same figure as PDF beside it.
"""
import argparse
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def attr(g, key, default=""):
    v = g.attrs.get(key, default)
    return v.decode() if isinstance(v, bytes) else v


def load(path, frame=None):
    runs = []
    with h5py.File(path, "r") as f:
        if "runs" not in f:
            sys.exit(f"{path}: no /runs group (not an xpbd-bench results file?)")
        for name, g in f["runs"].items():
            if attr(g, "level", "simulation") != "simulation" or "dual_residual" not in g:
                continue
            it = np.asarray(g["iteration"])
            fr = np.asarray(g["frame"])
            sub = np.asarray(g["substep"])
            keep = np.ones_like(it, dtype=bool) if frame is None else fr == frame
            # Cumulative wall time: each substep's clock restarts at 0.
            wt = np.asarray(g["wall_time"], dtype=float)
            starts = np.flatnonzero(it == 0)
            cum = wt.copy()
            offset = 0.0
            for k, s in enumerate(starts):
                e = starts[k + 1] if k + 1 < len(starts) else len(wt)
                cum[s:e] = wt[s:e] + offset
                offset = cum[e - 1]
            runs.append(dict(
                name=name, solver=attr(g, "solver"), scene=attr(g, "scene"), status=attr(g, "status"),
                x=np.arange(keep.sum()), dual=np.asarray(g["dual_residual"])[keep],
                rel=np.asarray(g["relative_dual_residual"])[keep], time=cum[keep],
                substeps=len(np.unique(np.stack([fr, sub])[:, keep], axis=1).T) if keep.any() else 0))
    return runs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None, help="output PNG (default: beside RESULTS)")
    ap.add_argument("--relative", action="store_true", help="plot the residual relative to each substep's first")
    ap.add_argument("--frame", type=int, default=None, help="only this frame")
    a = ap.parse_args()
    if not os.path.exists(a.results):
        sys.exit(f"{a.results}: no such file")
    runs = load(a.results, a.frame)
    if not runs:
        sys.exit(f"{a.results}: no simulation runs to plot")
    out = a.out or os.path.splitext(a.results)[0] + "_convergence.png"
    key = "rel" if a.relative else "dual"
    ylabel = "relative dual residual" if a.relative else r"dual residual $\|C + \tilde\alpha\lambda\|_2$"
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        y = np.where(r[key] > 0, r[key], np.nan)
        label = f"{r['solver']} ({r['status']})"
        ax1.semilogy(r["x"], y, label=label, lw=1.6)
        ax2.loglog(np.maximum(r["time"], 1e-6), y, label=label, lw=1.6)
    scenes = sorted({r["scene"] for r in runs})
    ax1.set_xlabel("outer iteration" + (" (substeps concatenated)" if any(r["substeps"] > 1 for r in runs) else ""))
    ax2.set_xlabel("wall time [s]")
    for ax in (ax1, ax2):
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=9)
    fig.suptitle(f"{', '.join(scenes)}: dual residual per outer iteration")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=130)
    fig.savefig(os.path.splitext(out)[0] + ".pdf")
    print(f"wrote {out} and {os.path.splitext(out)[0]}.pdf")


if __name__ == "__main__":
    main()
