#!/usr/bin/env python3
"""Each tracked performance metric over the runs in results/perf/*.json.

  perf_history.py [--dir results/perf] [--baseline results/baselines/perf.json]
                  [--match REGEX] [-o plots/perf_history]

Runs are ordered by their commit time (then by when they ran). One figure per group —
linear-solver iterations, outer iterations per substep, AMG levels/complexity, and the timed
ratios to the triad reference — with one small panel per metric; the baseline's value is the
dashed line. Writes <out>_<group>.png and prints what it wrote.
"""
import argparse
import glob
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import xbruns  # noqa: E402

GROUPS = [
    ("iterations", "linear-solver iterations to tolerance", lambda kind: kind == "iterations"),
    ("outer_iterations", "outer iterations per substep", lambda kind: kind == "outer_iterations"),
    ("amg", "AMG levels and complexities",
     lambda kind: kind in ("levels", "operator_complexity", "grid_complexity")),
    ("time", "time / triad time", lambda kind: kind == "time/triad"),
]


def tracked(record):
    """{metric: (kind, value)} of one perf JSON: gated numeric metrics and timed ratios."""
    out = {}
    for name, m in record.get("deterministic", {}).get("metrics", {}).items():
        if isinstance(m.get("value"), (int, float)) and m["kind"] not in ("info", "size"):
            out[name] = (m["kind"], float(m["value"]))
    for name, r in record.get("timed_ratios", {}).items():
        out[name] = ("time/triad", float(r))
    return out


def load_runs(folder):
    runs = []
    for path in glob.glob(os.path.join(folder, "*.json")):
        try:
            with open(path) as f:
                rec = json.load(f)
        except (OSError, json.JSONDecodeError) as e:
            print(f"perf_history: skipping {path}: {e}", file=sys.stderr)
            continue
        git = rec.get("git", {})
        label = git.get("sha", os.path.basename(path))[:8] + ("*" if git.get("dirty") else "")
        runs.append((git.get("commit_time", ""), rec.get("created", ""), label, tracked(rec)))
    runs.sort(key=lambda r: (r[0], r[1]))
    return runs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--dir", default=os.path.join(root, "results", "perf"))
    ap.add_argument("--baseline", default=os.path.join(root, "results", "baselines", "perf.json"))
    ap.add_argument("--match", default="", help="only metrics whose name matches this regex")
    ap.add_argument("-o", "--out", default=os.path.join(root, "plots", "perf_history"))
    a = ap.parse_args(argv)

    runs = load_runs(a.dir)
    if not runs:
        sys.exit(f"perf_history: no perf JSON files in {a.dir} (make perf writes them)")
    base = {}
    if os.path.exists(a.baseline):
        with open(a.baseline) as f:
            base = tracked(json.load(f))
    pattern = re.compile(a.match)
    names = {}
    for _, _, _, t in runs:
        for n, (kind, _) in t.items():
            if pattern.search(n):
                names[n] = kind
    labels = [r[2] for r in runs]
    xs = list(range(len(runs)))
    wrote = 0
    for key, title, select in GROUPS:
        metrics = sorted(n for n, k in names.items() if select(k))
        if not metrics:
            continue
        cols = min(4, len(metrics))
        rows = math.ceil(len(metrics) / cols)
        fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.6 * rows), squeeze=False)
        for ax, n in zip(axes.flat, metrics):
            ys = [r[3][n][1] if n in r[3] else float("nan") for r in runs]
            ax.plot(xs, ys, "o-", ms=3, lw=1)
            if n in base:
                ax.axhline(base[n][1], ls="--", lw=0.8, color="gray")
            ax.set_title(n, fontsize=7)
            ax.tick_params(labelsize=6)
            ax.set_xticks(xs)
            ax.set_xticklabels(labels, rotation=60, fontsize=5)
        for ax in list(axes.flat)[len(metrics):]:
            ax.axis("off")
        fig.suptitle(f"{title} over {len(runs)} runs (dashed: baseline)", fontsize=10)
        fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / fig.get_figheight()))
        path = f"{a.out}_{key}.png"
        xbruns.write_figure(fig, path, dpi=90)
        plt.close(fig)
        print(f"perf_history: wrote {path} ({len(metrics)} metrics)")
        wrote += 1
    if not wrote:
        sys.exit("perf_history: no tracked metric matched")
    return 0


if __name__ == "__main__":
    sys.exit(main())
