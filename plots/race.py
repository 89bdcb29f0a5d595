#!/usr/bin/env python3
"""The race's figures and summary (figures/race.py runs it; this redraws from its data).

usage: python3 plots/race.py DATA_DIR [--out plots/race] [--spec figures/race/race.toml]

DATA_DIR holds <scene>/<size>/<method>.<form>.<forcing>.h5, one run each. Draws, per scene,
OUT/race_<scene>.png (relative dual residual against wall time within the frame, one panel per
size, each method in its chosen form at each forcing rule), OUT/race_crossover.png (time per outer
iteration against dual rows, per method) and writes OUT/summary.md: per size, the time each entry
takes to reach the relative dual residual exact CHOLMOD reaches at the end of the frame (within
5 %), its wall time, final residual, time per outer iteration and mean linear iterations.
"""
import argparse
import math
import os
import sys
import tomllib

import numpy as np

import xbruns

DATASETS = ("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "wall_time",
            "linear_iterations", "linear_setup_time", "linear_solve_time", "fill_time", "linear_tolerance")
TARGET_SLACK = 1.05  # "reaches" exact CHOLMOD's final residual: within 5 %


def toml_text(v):
    """A value as --set text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def load_entries(data_dir):
    """{scene: {size: [entry]}}, entry = dict(method, form, forcing, run)."""
    out = {}
    if not os.path.isdir(data_dir):
        return out
    for scene in sorted(os.listdir(data_dir)):
        for size in sorted(os.listdir(os.path.join(data_dir, scene))):
            folder = os.path.join(data_dir, scene, size)
            for f in sorted(os.listdir(folder)):
                if not f.endswith(".h5") or f.endswith(".part.h5"):  # .part.h5: a run still going
                    continue
                method, form, forcing = f[:-3].rsplit(".", 2)
                runs = xbruns.load(os.path.join(folder, f), datasets=DATASETS)
                if runs:
                    out.setdefault(scene, {}).setdefault(size, []).append(
                        dict(method=method, form=form, forcing=forcing, run=runs[-1]))
    return out


def per_iteration(run):
    a = run["attrs"]
    n = float(a.get("outer_iterations", 0))
    return float(a["wall_time"]) / n if n > 0 else math.nan


def chosen_forms(sizes, order):
    """Each method's form: the faster per outer iteration at the smallest size (fixed forcing)."""
    smallest = min(sizes, key=lambda s: min(float(e["run"]["attrs"].get("rows", 0)) for e in sizes[s]))
    forms = {}
    for e in sizes[smallest]:
        if e["form"] == "none":
            forms[e["method"]] = "none"
        elif e["forcing"] == "fixed":
            best = forms.get(e["method"])
            t = per_iteration(e["run"])
            if best is None or t < best[1]:
                forms[e["method"]] = (e["form"], t)
    forms = {k: (v if v == "none" else v[0]) for k, v in forms.items()}
    return {k: forms[k] for k in order if k in forms} | forms


def raced(sizes, forms):
    """The entries in each method's chosen form, per size."""
    return {s: [e for e in es if forms.get(e["method"]) == e["form"]] for s, es in sizes.items()}


def trajectory(run):
    d = run["data"]
    m = xbruns.substep_mask(run, 0, 0)
    return np.asarray(d["wall_time"], dtype=float)[m], np.asarray(d["relative_dual_residual"], dtype=float)[m]


def time_to(run, target):
    t, rel = trajectory(run)
    hit = np.flatnonzero(rel <= target * TARGET_SLACK)
    return float(t[hit[0]]) if len(hit) else math.nan


def exact_target(entries):
    for e in entries:
        if e["method"] == "cholmod" and e["forcing"] == "fixed":
            return float(e["run"]["attrs"]["relative_dual_residual"])
    return math.nan


def label(e):
    return e["method"] + ("" if e["forcing"] in ("fixed", "none") or e["method"] == "cholmod" else " (EW)")


def size_key(entries):
    return min(float(e["run"]["attrs"].get("rows", 0)) for e in entries)


def draw_scene(plt, scene, sizes, out):
    names = sorted(sizes, key=lambda s: size_key(sizes[s]))
    fig, axes = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.2), squeeze=False)
    colours = plt.get_cmap("tab20").colors
    for ax, size in zip(axes[0], names):
        ax.set_prop_cycle(color=colours)
        for e in sorted(sizes[size], key=label):
            t, rel = trajectory(e["run"])
            style = "--" if e["forcing"] == "eisenstat_walker" else "-"
            ax.semilogy(t, rel, style, marker=".", label=f"{label(e)} [{e['form']}]")
        target = exact_target(sizes[size])
        if math.isfinite(target):
            ax.axhline(target, color="grey", lw=0.8, ls=":")
            ax.set_ylim(target / 3, 2.0)  # a diverged run's climb would hide the race
        ax.set_title(f"{scene} {size}")
        ax.set_xlabel("wall time within the frame (s)")
        ax.set_ylabel("relative dual residual")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, f"race_{scene}.png"))
    plt.close(fig)


def draw_crossover(plt, scenes, out):
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.2), squeeze=False)
    for ax, (scene, sizes) in zip(axes[0], scenes.items()):
        lines = {}
        for size, es in sizes.items():
            for e in es:
                lines.setdefault(label(e), []).append((float(e["run"]["attrs"].get("rows", 0)), per_iteration(e["run"])))
        for name, pts in sorted(lines.items()):
            pts.sort()
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "-o", ms=3, label=name)
        ax.set_title(scene)
        ax.set_xlabel("dual rows (constraints)")
        ax.set_ylabel("s per outer iteration")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, "race_crossover.png"))
    plt.close(fig)


def mean_linear_iterations(run):
    its = np.asarray(run["data"].get("linear_iterations", []), dtype=float)
    its = its[np.asarray(run["data"]["iteration"]) > 0] if len(its) else its
    return float(its.mean()) if len(its) else math.nan


def summary(scenes, forms_by_scene):
    lines = ["# The race: time to exact CHOLMOD's end-of-frame residual", "",
             "Each entry in its own process; `time to target` is the wall time within the frame at which the "
             f"relative dual residual first comes within {int(round((TARGET_SLACK - 1) * 100))} % of what exact "
             "CHOLMOD reaches at the end of the frame (— never). EW: linear.forcing = eisenstat_walker.", ""]
    for scene, sizes in scenes.items():
        forms = forms_by_scene[scene]
        lines.append(f"## {scene}")
        lines.append("")
        lines.append("forms: " + ", ".join(f"{k} {v}" for k, v in forms.items() if v != "none"))
        lines.append("")
        for size in sorted(sizes, key=lambda s: size_key(sizes[s])):
            es = sizes[size]
            target = exact_target(es)
            rows = int(size_key(es))
            lines.append(f"### {size} ({rows} dual rows; target {xbruns.fmt(target)})")
            lines.append("")
            lines.append("| method | form | time to target s | wall s | final rel. residual | s / outer it. | linear its | status |")
            lines.append("|---|---|---|---|---|---|---|---|")
            ranked = sorted(es, key=lambda e: (math.isnan(time_to(e["run"], target)), time_to(e["run"], target)))
            for e in ranked:
                a = e["run"]["attrs"]
                tt = time_to(e["run"], target)
                lines.append(f"| {label(e)} | {e['form']} | {'—' if math.isnan(tt) else f'{tt:.2f}'} | "
                             f"{float(a['wall_time']):.2f} | {float(a['relative_dual_residual']):.3g} | "
                             f"{per_iteration(e['run']):.3g} | {xbruns.fmt(mean_linear_iterations(e['run']))} | "
                             f"{a.get('status')} |")
            lines.append("")
    return "\n".join(lines) + "\n"


def draw(data_dir, out, spec):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    order = list(spec.get("methods", {}))
    scenes, forms_by_scene = {}, {}
    for scene, sizes in load_entries(data_dir).items():
        forms_by_scene[scene] = chosen_forms(sizes, order)
        scenes[scene] = raced(sizes, forms_by_scene[scene])
    if not scenes:
        print(f"race: no runs under {data_dir}", file=sys.stderr)
        return
    os.makedirs(out, exist_ok=True)
    for scene, sizes in scenes.items():
        draw_scene(plt, scene, sizes, out)
    draw_crossover(plt, scenes, out)
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write(summary(scenes, forms_by_scene))
    print(f"wrote {os.path.join(out, 'summary.md')}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "race"))
    ap.add_argument("--spec", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                                   "figures", "race", "race.toml"))
    args = ap.parse_args()
    with open(args.spec, "rb") as fh:
        spec = tomllib.load(fh)
    draw(args.data, args.out, spec)


if __name__ == "__main__":
    main()
