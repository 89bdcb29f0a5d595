#!/usr/bin/env python3
"""Solver × case map of run statuses.

usage: python3 plots/stability.py RESULTS.h5 [-o OUT.png] [--case KEY[,KEY...]]

Cases are the values of --case (default: the attribute `variant` where runs differ in it, else the
swept keys of a sweep, else the scene). Each cell is coloured by status (ok, max_iterations,
over_budget, out_of_memory, diverged, nan, breakdown, error) and shows it with the final relative value of the run's
own stop measure (the dual residual; ‖∇E‖ under Newton, vbd and avbd: final_relative_convergence);
with repeats, the worst status is shown. Writes PNG and PDF and prints the table.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.colors  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import xbruns  # noqa: E402


def case_keys(runs, arg):
    if arg:
        return arg.split(",")
    variants = {str(r["attrs"].get("variant", "")) for r in runs}
    if len(variants) > 1:
        return ["variant"]
    keys = list(xbruns.swept(runs[0]))
    return keys or (["variant"] if variants - {"", "none"} else ["scene"])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None)
    ap.add_argument("--case", default=None, help="attribute(s) that name a case, comma-separated")
    ap.add_argument("--title", default=None)
    a = ap.parse_args()

    runs = xbruns.load(a.results, datasets=())
    if not runs:
        sys.exit(f"{a.results}: no simulation runs")
    keys = case_keys(runs, a.case)
    cells = {}
    for r in runs:
        at = r["attrs"]
        case = " ".join(f"{k}={xbruns.fmt(at.get(k, '-'))}" if len(keys) > 1 or k not in ("variant", "scene")
                        else str(at.get(k, "-")) for k in keys)
        cells.setdefault((at.get("solver", "?"), case), []).append(
            (at.get("status", "error"), xbruns.as_number(at.get("final_relative_convergence", at.get("relative_dual_residual")))))
    solvers = sorted({s for s, _ in cells})
    cases = sorted({c for _, c in cells}, key=lambda c: [(xbruns.as_number(p.split("=")[-1]) is None,
                                                          xbruns.as_number(p.split("=")[-1]) or 0, p)
                                                         for p in c.split(" ")])
    rank = {s: i for i, s in enumerate(xbruns.STATUS_ORDER)}
    fig, ax = plt.subplots(figsize=(1.8 + 1.25 * len(cases), 1.0 + 0.55 * len(solvers)))
    colours, texts = [], []
    for s in solvers:
        crow, trow = [], []
        for c in cases:
            v = cells.get((s, c))
            if not v:
                crow.append(matplotlib.colors.to_rgb("#ffffff"))
                trow.append("-")
                continue
            status, rel = max(v, key=lambda x: rank.get(x[0], 99))
            crow.append(matplotlib.colors.to_rgb(xbruns.STATUS_COLOURS.get(status, "#bdbdbd")))
            trow.append(status + ("" if rel is None else f"\n{rel:.1e}"))
            print(f"{s}\t{c}\t{status}\t{rel}")
        colours.append(crow)
        texts.append(trow)
    ax.imshow(colours, aspect="auto")
    for i, row in enumerate(texts):
        for j, t in enumerate(row):
            ax.text(j, i, t, ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(cases)), cases, rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(len(solvers)), solvers)
    ax.set_title(a.title or "status per solver and case (cell: status, final relative dual residual)")
    fig.tight_layout()
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "stability"))


if __name__ == "__main__":
    main()
