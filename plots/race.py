#!/usr/bin/env python3
"""The race's figures and summary (figures/race.py runs it; this redraws from its data).

usage: python3 plots/race.py DATA_DIR [--out plots/race] [--spec figures/race/race.toml]

DATA_DIR holds <scene>/<size>/<method>.<form>.<forcing>.h5, one run each, and a
<method>.<form>.<forcing>.failed.json record for a run whose process left none. The rules (form,
target, best entry, what counts as finished) are plots/race_rules.py's, the driver's too. Draws,
per scene, OUT/race_<scene>.png (relative dual residual against wall time within the frame, one
panel per size, one line per method at its best; a row for the position error and one for the
Newton residual where the runs record them), OUT/race_<scene>_variants.png (every forcing rule,
precision and stop norm of the methods that have several), OUT/race_crossover.png (time per outer
iteration against dual rows, per method) and writes OUT/summary.md.
"""
import argparse
import json
import math
import os
import re
import sys
import tomllib

import numpy as np

import race_rules as rules
import xbruns

DATASETS = ("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "wall_time",
            "linear_iterations", "linear_setup_time", "linear_solve_time", "fill_time", "linear_tolerance")
OPTIONAL = ("position_error", "newton_residual")  # read where the schema and the run have them
METRIC_LABELS = {"relative_dual_residual": "relative dual residual", "position_error": "position error",
                 "newton_residual": "Newton residual (relative)"}


def datasets():
    return DATASETS + tuple(d for d in OPTIONAL if d in xbruns.dataset_names())


def toml_text(v):
    """A value as --set text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def safe_name(label):
    """A size label as a folder name (bunny:12k -> bunny_12k)."""
    return re.sub(r"[^A-Za-z0-9._-]", "_", label)


def failure_record(path, cmd, code, message, seconds):
    with open(path, "w") as fh:
        json.dump({"status": "failed", "exit": code, "message": message, "wall_time": seconds,
                   "command": cmd}, fh)


def load_entries(data_dir):
    """{scene: {size: [entry]}}, entry = dict(method, form, forcing, run); a failure record's run
    has attrs only (status failed, its exit code and message)."""
    out = {}
    if not os.path.isdir(data_dir):
        return out
    for scene in sorted(os.listdir(data_dir)):
        for size in sorted(os.listdir(os.path.join(data_dir, scene))):
            folder = os.path.join(data_dir, scene, size)
            for f in sorted(os.listdir(folder)):
                path = os.path.join(folder, f)
                if f.endswith(".failed.json"):
                    with open(path) as fh:
                        run = {"attrs": json.load(fh)}
                    stem = f[:-len(".failed.json")]
                elif f.endswith(".h5") and not f.endswith(".part.h5"):  # .part.h5: a run still going
                    runs = xbruns.load(path, datasets=datasets())
                    if not runs:
                        continue
                    run, stem = runs[-1], f[:-3]
                else:
                    continue
                method, form, forcing = stem.rsplit(".", 2)
                out.setdefault(scene, {}).setdefault(size, []).append(dict(method=method, form=form, forcing=forcing,
                                                                           run=run))
    return out


def ordered_sizes(sizes, scene_spec):
    """The sizes in the spec's order (smallest first), then any others by dual rows."""
    order = [safe_name(z["label"]) for z in (scene_spec or {}).get("sizes", [])]
    rows = {s: max([float(e["run"]["attrs"].get("rows", 0)) for e in es] + [0]) for s, es in sizes.items()}
    return sorted(sizes, key=lambda s: (order.index(s) if s in order else len(order), rows[s]))


def chosen_forms(smallest_entries, methods):
    """Each method's form by rules.form_of from its fixed-forcing runs at the smallest size, in the
    spec's order (a variant after its method)."""
    by_method = {}
    for e in smallest_entries:
        if e["form"] == "none":
            by_method[e["method"]] = None
        elif e["forcing"] == "fixed" and by_method.get(e["method"], {}) is not None:
            by_method.setdefault(e["method"], {})[e["form"]] = e["run"]
    forms = {}
    for m in sorted(by_method, key=lambda m: (list(methods).index(m) if m in methods else len(methods), m)):
        forms[m] = "none" if by_method[m] is None else rules.form_of(m, methods, by_method[m], forms)
    return forms


def label(e):
    return e["method"] + ("" if e["forcing"] in ("fixed", "none") or e["method"] == "cholmod" else " (EW)")


def exact_run(entries):
    return next((e["run"] for e in entries if e["method"] == "cholmod" and e["forcing"] == "fixed"), None)


class Scene:
    """One scene's entries in their chosen forms, per size, with its targets and families."""

    def __init__(self, name, sizes, spec):
        methods = spec.get("methods", {})
        self.name, self.methods = name, methods
        self.family = lambda m: methods.get(m, {}).get("variant_of", m)
        self.order = ordered_sizes(sizes, spec.get("scenes", {}).get(name))
        self.raw_smallest = sizes[self.order[0]]
        self.forms = chosen_forms(self.raw_smallest, methods)
        self.sizes, self.dropped = {}, []
        for s in self.order:
            keep = [e for e in sizes[s] if self.forms.get(e["method"], e["form"]) == e["form"]]
            if s != self.order[0]:
                self.dropped += [f"{label(e)} [{e['form']}] at {s}" for e in sizes[s] if e not in keep]
            self.sizes[s] = keep
        self.targets = {s: {m: rules.target(exact_run(es), m) for m in rules.METRICS} for s, es in self.sizes.items()}
        fams = [self.family(m) for m in methods] + sorted({self.family(e["method"]) for es in sizes.values() for e in es})
        self.families = list(dict.fromkeys(fams))

    def rows(self, s):
        return int(max([float(e["run"]["attrs"].get("rows", 0)) for e in self.sizes[s]] + [0]))

    def best_by_family(self, s):
        out = {}
        for fam in self.families:
            runs = [e for e in self.sizes[s] if self.family(e["method"]) == fam]
            b = rules.best([e["run"] for e in runs], self.targets[s]["relative_dual_residual"])
            if b is not None:
                out[fam] = next(e for e in runs if e["run"] is b)
        return out

    def metrics(self):
        return [m for m in rules.METRICS if any(rules.series(e["run"], m) is not None
                                                for es in self.sizes.values() for e in es)]


def colour_of(families):
    palette = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
               "#7f7f7f", "#bcbd22"]
    return {f: palette[i % len(palette)] for i, f in enumerate(families)}


def panel(ax, sc, s, metric, entries, colour, style):
    for e in entries:
        ser = rules.series(e["run"], metric)
        if ser is not None:
            ax.semilogy(ser[0], ser[1], style(e), color=colour(e), marker=".", ms=3, lw=1.4,
                        label=f"{label(e)} [{e['form']}]")
    goal = sc.targets[s][metric]
    if math.isfinite(goal):
        ax.axhline(goal, color="black", lw=0.8, ls=":")
        if metric == "relative_dual_residual":
            ax.set_ylim(goal / 3, 2.0)  # a diverged run's climb would hide the race
    ax.set_title(f"{sc.name} {s}")
    ax.set_xlabel("wall time within the frame (s)")
    ax.set_ylabel(METRIC_LABELS[metric])
    ax.grid(True, which="both", alpha=0.3)


def draw_scene(plt, sc, out):
    """One line per method at its best; a row per metric the runs record."""
    metrics, colours = sc.metrics() or ["relative_dual_residual"], colour_of(sc.families)
    fig, axes = plt.subplots(len(metrics), len(sc.order), figsize=(5.4 * len(sc.order), 4.2 * len(metrics)),
                             squeeze=False, constrained_layout=True)
    for j, s in enumerate(sc.order):
        best = list(sc.best_by_family(s).values())
        for i, metric in enumerate(metrics):
            panel(axes[i][j], sc, s, metric, best, lambda e: colours[sc.family(e["method"])], lambda e: "-")
    if axes[0][0].get_legend_handles_labels()[0]:
        axes[0][0].legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, f"race_{sc.name}.png"))
    plt.close(fig)


def draw_variants(plt, sc, out):
    """Per method with several entries (forcing rules, precisions, stop norms), all of them."""
    fams = [f for f in sc.families if sum(sc.family(e["method"]) == f for e in sc.sizes[sc.order[0]]) > 1]
    if not fams:
        return
    fig, axes = plt.subplots(len(fams), len(sc.order), figsize=(5.4 * len(sc.order), 4.0 * len(fams)), squeeze=False, constrained_layout=True)
    for i, fam in enumerate(fams):
        present = {e["method"] for es in sc.sizes.values() for e in es if sc.family(e["method"]) == fam}
        names = [m for m in sc.methods if m in present] + sorted(present - set(sc.methods))
        colours = colour_of(names)
        for j, s in enumerate(sc.order):
            es = [e for e in sc.sizes[s] if sc.family(e["method"]) == fam]
            panel(axes[i][j], sc, s, "relative_dual_residual", es, lambda e: colours[e["method"]],
                  lambda e: "--" if e["forcing"] == "eisenstat_walker" else "-")
            axes[i][j].set_title(f"{sc.name} {s}: {fam}")
            if axes[i][j].get_legend_handles_labels()[0]:
                axes[i][j].legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, f"race_{sc.name}_variants.png"))
    plt.close(fig)


def draw_crossover(plt, scenes, out):
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.4 * len(scenes), 4.2), squeeze=False, constrained_layout=True)
    for ax, sc in zip(axes[0], scenes):
        colours, lines = colour_of(sc.families), {}
        for s in sc.order:
            for fam, e in sc.best_by_family(s).items():
                if rules.status(e["run"]) in rules.PACED:  # a timeout measured its pace too
                    lines.setdefault(fam, []).append((sc.rows(s), rules.per_iteration(e["run"])))
        for fam, pts in lines.items():
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "-o", ms=4, color=colours[fam], label=fam)
        ax.set_title(sc.name)
        ax.set_xlabel("dual rows (constraints)")
        ax.set_ylabel("s per outer iteration (best entry)")
        ax.grid(True, which="both", alpha=0.3)
        if lines:
            ax.legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, "race_crossover.png"))
    plt.close(fig)


def mean_linear_iterations(run):
    its = np.asarray(run.get("data", {}).get("linear_iterations", []), dtype=float)
    its = its[np.asarray(run["data"]["iteration"]) > 0] if len(its) else its
    return float(its.mean()) if len(its) else math.nan


def lagged_note(e):
    """What the lagged factor did, from the run's statistics; None for other runs."""
    a = e["run"]["attrs"]
    if "refactorisations_in_solve" not in a or "outer_iterations" not in a:  # a timeout's counts are real too
        return None
    kept, refac = int(float(a.get("lagged_setups", 0))), int(float(a["refactorisations_in_solve"]))
    bound = a.get("cholmod.lagged_max_iterations", "?")
    text = (f"{label(e)}: of {kept} steps that kept an older factor, {refac} hit the bound of {bound} CG "
            f"iterations (`cholmod.lagged_max_iterations`) and refactorised inside the solve; "
            f"{int(float(a.get('factorisations', 0)))} factorisations in {int(float(a['outer_iterations']))} steps")
    if kept and refac >= kept / 2:
        text += f": here lagged CHOLMOD is exact CHOLMOD plus up to {bound} wasted CG iterations a step"
    return text + "."


def rank(t):
    """Sort key of a time that may be NaN (never): those last."""
    return (math.isnan(t), 0.0 if math.isnan(t) else t)


def fmt_time(t):
    return "—" if math.isnan(t) else f"{t:.2f}"


def status_text(run):
    a = run["attrs"]
    if a.get("status") == "failed":
        said = str(a.get("message", "")).strip().splitlines()
        return f"failed (exit {a.get('exit')}{': ' + said[-1].replace('|', '/') if said else ''})"
    return str(a.get("status"))


def size_table(sc, s):
    goal, extra = sc.targets[s], [m for m in ("position_error", "newton_residual") if m in sc.metrics()]
    head = ["method", "form", "time to target s"] + [f"time to {METRIC_LABELS[m]} s" for m in extra] + \
        ["wall s", "final rel. residual", "s / outer it.", "linear its", "status", "load"]
    lines = [f"### {s} ({sc.rows(s)} dual rows; target {xbruns.fmt(goal['relative_dual_residual'])}"
             + "".join(f", {METRIC_LABELS[m]} {xbruns.fmt(goal[m])}" for m in extra) + ")", "",
             "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    ranked = sorted(sc.sizes[s], key=lambda e: rank(rules.time_to(e["run"], goal["relative_dual_residual"])))
    for e in ranked:
        r, a = e["run"], e["run"]["attrs"]
        cells = [label(e), e["form"], fmt_time(rules.time_to(r, goal["relative_dual_residual"]))]
        cells += [fmt_time(rules.time_to(r, goal[m], m)) for m in extra]
        cells += [f"{float(a.get('wall_time', math.nan)):.2f}", xbruns.fmt(rules.final_value(r, "relative_dual_residual")),
                  xbruns.fmt(rules.per_iteration(r)), xbruns.fmt(mean_linear_iterations(r)), status_text(r),
                  xbruns.fmt(float(a.get("load_average", math.nan)))]
        lines.append("| " + " | ".join(cells) + " |")
    notes = [n for n in (lagged_note(e) for e in ranked) if n]
    made = sorted(str(e["run"]["attrs"]["created"]) for e in ranked if "created" in e["run"]["attrs"])
    if made:
        notes.append(f"runs made {made[0]} – {made[-1]}; load: the 1-min load average at each run's start.")
    return lines + [""] + [f"- {n}" for n in notes] + ([""] if notes else [])


def summary(scenes):
    slack = int(round((rules.TARGET_SLACK - 1) * 100))
    lines = ["# The race: time to exact CHOLMOD's end-of-frame residual", "",
             "Each entry in its own process; `time to target` is the wall time within the frame at which the "
             f"relative dual residual first comes within {slack} % of what exact CHOLMOD reaches at the end of the "
             "frame (— never; no target where exact CHOLMOD did not finish). EW: linear.forcing = eisenstat_walker. "
             "Rules: plots/race_rules.py.", ""]
    lines += headline(scenes)
    for sc in scenes:
        smallest = sc.order[0]
        forms = []
        for m, f in sc.forms.items():
            if f == "none":
                continue
            base = rules.base_of(m, sc.methods)
            t = {e["form"]: f"{xbruns.fmt(rules.per_iteration(e['run']))} {rules.status(e['run'])}"
                 for e in chosen_candidates(sc, m)}
            forms.append(f"{m} {f} (" + (f"as {base}" if base else ", ".join(f"{k} {v}" for k, v in sorted(t.items())))
                         + ")")
        lines += [f"## {sc.name}", "", f"forms (s per outer iteration at {smallest} with fixed forcing, and the run's "
                  "status; a run that broke down or diverged does not count): " + "; ".join(forms), ""]
        for s in sc.order:
            lines += size_table(sc, s)
        if sc.dropped:
            lines += ["Runs in a form other than the chosen one (not in the tables): " + ", ".join(sc.dropped), ""]
    return "\n".join(lines) + "\n"


def headline(scenes):
    """Each method at its best: per scene and size, the best entry's time to the target (s)."""
    fams = list(dict.fromkeys(f for sc in scenes for f in sc.families))
    lines = ["## Each method at its best", "",
             "Time to the target (s) of each method's best entry (its forcing rule and variant in brackets; "
             "— never, with its status); the target: exact CHOLMOD's relative dual residual at the end of the frame.", "",
             "| scene, size (dual rows) | target | " + " | ".join(fams) + " |", "|---|---|" + "---|" * len(fams)]
    for sc in scenes:
        for s in sc.order:
            best, cells = sc.best_by_family(s), []
            for f in fams:
                e = best.get(f)
                if e is None:
                    cells.append("")
                    continue
                tt = rules.time_to(e["run"], sc.targets[s]["relative_dual_residual"])
                tag = ", ".join(x for x in (e["method"] if e["method"] != f else "",
                                            "EW" if e["forcing"] == "eisenstat_walker" else "") if x)
                cells.append((f"{tt:.2f}" if math.isfinite(tt) else f"— ({rules.status(e['run'])})")
                             + (f" ({tag})" if tag else ""))
            lines.append(f"| {sc.name} {s} ({sc.rows(s)}) | {xbruns.fmt(sc.targets[s]['relative_dual_residual'])} | "
                         + " | ".join(cells) + " |")
    return lines + [""]


def chosen_candidates(sc, method):
    return [e for e in sc.raw_smallest if e["method"] == method and e["forcing"] == "fixed"]


def draw(data_dir, out, spec):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = []
    for name, sizes in load_entries(data_dir).items():
        scenes.append(Scene(name, sizes, spec))
    if not scenes:
        print(f"race: no runs under {data_dir}", file=sys.stderr)
        return
    os.makedirs(out, exist_ok=True)
    for sc in scenes:
        draw_scene(plt, sc, out)
        draw_variants(plt, sc, out)
    draw_crossover(plt, scenes, out)
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write(summary(scenes))
    print(f"wrote {os.path.join(out, 'summary.md')}")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data")
    ap.add_argument("--out", default=os.path.join(here, "race"))
    ap.add_argument("--spec", default=os.path.join(os.path.dirname(here), "figures", "race", "race.toml"))
    args = ap.parse_args()
    with open(args.spec, "rb") as fh:
        spec = tomllib.load(fh)
    draw(args.data, args.out, spec)


if __name__ == "__main__":
    main()
