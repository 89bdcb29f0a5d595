#!/usr/bin/env python3
"""The race's figures and summary (figures/race.py runs it; this redraws from its data).

usage: python3 plots/race.py DATA_DIR [--out plots/race] [--spec figures/race/race.toml] [--readme README.md]
                              [--pick docs/results/vbd_pick.md]

DATA_DIR holds <scene>/<size>/<outer>.<linear>.<forcing>.h5, one run each (with --reference), and a
<outer>.<linear>.<forcing>.failed.json record for a run whose process left none. The rules (the
time to a position error, a run that never reaches it, a reference that did not converge, the best
entry) are plots/race_rules.py's, the driver's too. Draws, per scene, OUT/race_<scene>.png (the
position error against the backward-Euler solution against wall time within the frame: a row per
outer method, a panel per size, a line per linear method at its best forcing rule) and writes
OUT/summary.md; a DATA_DIR/../timings.tsv is copied to OUT. --readme FILE: the headline table
(time to each threshold of each outer method at its best) replaces the one between the race-table
markers in FILE (README.md's), so that publishing a race is one command. --pick FILE: the spec's
[pick] comparison ("XPBD, VBD, Newton: which to pick", plots/race_pick.py) as a generated page
(docs/results/vbd_pick.md); summary.md has it too.
"""
import argparse
import json
import math
import os
import re
import shutil
import sys
import tomllib

import numpy as np

import race_pick
import race_rules as rules
import race_scaling
import xbruns

DATASETS = ("frame", "substep", "iteration", "wall_time", "relative_dual_residual", "linear_iterations",
            rules.METRIC, "reference/source") + xbruns.REFERENCE_DATASETS
README_BEGIN = "<!-- race table: begin (python3 plots/race.py DATA --readme README.md writes it) -->"
README_END = "<!-- race table: end -->"


def datasets():
    return tuple(d for d in DATASETS if d in xbruns.dataset_names())


def toml_text(v):
    """A value as --set text."""
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def safe_name(label):
    """A size label as a folder name (bunny:12k -> bunny_12k)."""
    return re.sub(r"[^A-Za-z0-9._-]", "_", label)


def failure_record(path, cmd, code, message, seconds, load=None):
    with open(path, "w") as fh:
        json.dump({"status": "failed", "exit": code, "message": message, "wall_time": seconds,
                   "command": cmd, **({"load_average": load} if load is not None else {})}, fh)


def load_entries(data_dir):
    """{scene: {size: [entry]}}, entry = dict(outer, linear, forcing, run); a failure record's run
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
                elif f.endswith(".h5") and not f.endswith(".part.h5") and os.path.isfile(path):
                    runs = xbruns.load(path, datasets=datasets())
                    if not runs:
                        continue
                    run, stem = runs[-1], f[:-3]
                else:
                    continue  # a run still going (.part.h5), the _state folder
                parts = stem.rsplit(".", 2)
                if len(parts) == 3:
                    out.setdefault(scene, {}).setdefault(size, []).append(
                        dict(outer=parts[0], linear=parts[1], forcing=parts[2], run=run))
    return out


def reference_passes(data_dir):
    """{(scene, size): the attributes of the size's reference pass (figures/race.py)}."""
    out = {}
    for scene in sorted(os.listdir(data_dir)) if os.path.isdir(data_dir) else []:
        for size in sorted(os.listdir(os.path.join(data_dir, scene))):
            path = os.path.join(data_dir, scene, size, "_reference", "run.h5")
            runs = xbruns.load(path, datasets=()) if os.path.isfile(path) else []
            if runs:
                out[(scene, size)] = runs[-1]["attrs"]
    return out


def reference_note(sc, s):
    """How the size's reference was made, and how many entries read it rather than computing it."""
    a = getattr(sc, "references", {}).get(s)
    srcs = [str(e["run"].get("data", {}).get("reference/source", ["?"])[0]) for e in sc.sizes[s] if "data" in e["run"]]
    read = sum(1 for x in srcs if x == "read")
    text = f"{read} of {len(srcs)} entries read the size's stored reference"
    if a:
        verdict = "converged" if str(a.get("reference_substeps_unconverged", "1")) == "0" else "did not converge"
        text = (f"reference computed once ({float(a.get('reference_time', math.nan)):.1f} s, its process's peak "
                f"{float(a.get('peak_memory', math.nan)) / 1e9:.2f} GB; it {verdict}); " + text)
    return text + "."


def ordered(names, spec_order):
    return [n for n in spec_order if n in names] + sorted(set(names) - set(spec_order))


class Scene:
    """One scene's entries per size (in the spec's size order), its outer and linear methods."""

    def __init__(self, name, sizes, spec):
        self.name, self.spec = name, spec
        self.thresholds = sorted(spec.get("thresholds", [1e-2, 1e-3, 1e-4]), reverse=True)
        order = [safe_name(z["label"]) for z in spec.get("scenes", {}).get(name, {}).get("sizes", [])]
        self.order = ordered(sizes, order)
        self.sizes = {s: sizes[s] for s in self.order}
        every = [e for es in sizes.values() for e in es]
        self.outers = ordered({e["outer"] for e in every}, list(spec.get("outer", {})))
        self.linears = ordered({e["linear"] for e in every}, list(spec.get("linear", {})))

    def outer_label(self, o):
        return self.spec.get("outer", {}).get(o, {}).get("label", o)

    def rows(self, s):
        return int(max([float(e["run"]["attrs"].get("rows", 0)) for e in self.sizes[s]] + [0]))

    def pair_best(self, s):
        """{(outer, linear): entry}: each pair at its best forcing rule."""
        out = {}
        for o in self.outers:
            for m in self.linears:
                es = [e for e in self.sizes[s] if e["outer"] == o and e["linear"] == m]
                b = rules.best([e["run"] for e in es], self.thresholds)
                if b is not None:
                    out[(o, m)] = next(e for e in es if e["run"] is b)
        return out

    def outer_first(self, s, o, threshold):
        """The entry of outer method `o` that reaches `threshold` first; else its best entry."""
        es = [e for e in self.sizes[s] if e["outer"] == o]
        r = rules.first_to([e["run"] for e in es], threshold) or rules.best([e["run"] for e in es], self.thresholds)
        return next((e for e in es if e["run"] is r), None)


def colour_of(names):
    palette = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
               "#7f7f7f", "#bcbd22"]
    return {n: palette[i % len(palette)] for i, n in enumerate(names)}


def tag(e):
    return e["linear"] + (" (EW)" if e["forcing"] == "eisenstat_walker" else "")


def draw_scene(plt, sc, out):
    """A row per outer method, a panel per size, a line per linear method at its best."""
    colours = colour_of(sc.linears)
    fig, axes = plt.subplots(len(sc.outers), len(sc.order), figsize=(5.4 * len(sc.order), 3.8 * len(sc.outers)),
                             squeeze=False, constrained_layout=True)
    for j, s in enumerate(sc.order):
        best = sc.pair_best(s)
        for i, o in enumerate(sc.outers):
            ax = axes[i][j]
            for (oo, m), e in best.items():
                ser = rules.series(e["run"])
                if oo != o or ser is None:
                    continue
                ok, why = xbruns.reference_trusted(e["run"], min(sc.thresholds))
                ax.semilogy(ser[0], np.maximum(ser[1], 1e-300), "-" if ok else ":", color=colours[m], marker=".", ms=3,
                            lw=1.4, label=tag(e) + ("" if ok else f" ({why.split(' (')[0].split(':')[0]})"))
            for t in sc.thresholds:
                ax.axhline(t, color="black", lw=0.8, ls=":")
            ax.set_ylim(min(sc.thresholds) * 1e-3, 2.0)  # a converged run's 1e-16 would flatten the race
            ax.set_title(f"{sc.outer_label(o)}: {sc.name} {s}", fontsize=9)
            ax.set_xlabel("wall time within the frame (s)")
            ax.set_ylabel("position error")
            ax.grid(True, which="both", alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7)
    xbruns.save(fig, os.path.join(out, f"race_{sc.name}.png"))
    plt.close(fig)


def fmt_time(t):
    return "—" if t is None or (isinstance(t, float) and math.isnan(t)) else f"{t:.2f}"


def cell(e, threshold, name_linear=True):
    """A summary cell: the time to the threshold (and by what), or why there is none."""
    if e is None:
        return ""
    t, why = rules.verdict(e["run"], threshold)
    if t is not None:
        return f"{t:.2f}" + (f" ({tag(e)})" if name_linear else "")
    if why == rules.NEVER:
        return f"— ({xbruns.fmt(rules.smallest_error(e['run']))})"
    return f"— ({why if why != rules.NO_DATA else rules.status(e['run'])})"


def status_text(run):
    a = run["attrs"]
    if a.get("status") == "failed":
        said = str(a.get("message", "")).strip().splitlines()
        return f"failed (exit {a.get('exit')}{': ' + said[-1].replace('|', '/') if said else ''})"
    return str(a.get("status"))


def reference_text(run):
    """The reference's verdict and certificate: "converged, certified: error ≤ 3e-09 (trusted to
    3e-07)", or why not."""
    ok, why = xbruns.reference_verdict(run)
    if not ok:
        return why
    d = run.get("data", {})
    cert, est = d.get("reference/certified"), d.get("reference/error_estimate")
    if cert is None or est is None or len(cert) == 0:
        return "converged, no certificate recorded"
    if not int(cert[0]):
        note = d.get("reference/certificate_note")
        return "converged, not certified" + (f": {note[0]}" if note is not None and len(note) and str(note[0]) else "")
    return f"converged, certified: error ≤ {float(est[0]):.2g} (trusted to {100 * float(est[0]):.2g})"


def lagged_note(e):
    """What the lagged factor did, from the run's statistics; None for other runs."""
    a = e["run"]["attrs"]
    if "refactorisations_in_solve" not in a or "outer_iterations" not in a:
        return None
    kept, refac = int(float(a.get("lagged_setups", 0))), int(float(a["refactorisations_in_solve"]))
    bound = a.get("cholmod.lagged_max_iterations", "?")
    return (f"{e['outer']} + {tag(e)}: of {kept} steps that kept an older factor, {refac} hit the bound of {bound} CG "
            f"iterations and refactorised inside the solve; {int(float(a.get('factorisations', 0)))} factorisations "
            f"in {int(float(a['outer_iterations']))} steps.")


def mean_linear_iterations(run):
    d = run.get("data", {})
    its = np.asarray(d.get("linear_iterations", []), dtype=float)
    its = its[np.asarray(d["iteration"]) > 0] if len(its) else its
    return float(its.mean()) if len(its) else math.nan


def row(cells):
    """A Markdown table row; a | inside a cell (a message) is escaped."""
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"


def size_table(sc, s):
    ths = sc.thresholds
    head = ["outer method", "linear", "forcing"] + [f"time to {t:g} s" for t in ths] + \
        ["smallest error", "wall s", "reference s", "outer its", "s / outer it.", "linear its", "peak GB", "status",
         "reference", "load"]
    lines = [f"### {s} ({sc.rows(s)} dual rows)", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def key(e):
        return rules.rank_key(e["run"], ths)
    for e in sorted(sc.sizes[s], key=key):
        r, a = e["run"], e["run"]["attrs"]
        cells = [sc.outer_label(e["outer"]), e["linear"], e["forcing"]] + [cell(e, t, False) for t in ths]
        cells += [xbruns.fmt(rules.smallest_error(r)), xbruns.fmt(float(a.get("wall_time", math.nan))),
                  xbruns.fmt(float(a.get("reference_time", math.nan))), str(a.get("outer_iterations", "—")),
                  xbruns.fmt(rules.per_iteration(r)), xbruns.fmt(mean_linear_iterations(r)),
                  xbruns.fmt(float(a.get("peak_memory", math.nan)) / 1e9), status_text(r),
                  reference_text(r) if "data" in r else "—", xbruns.fmt(float(a.get("load_average", math.nan)))]
        lines.append(row(cells))
    notes = [reference_note(sc, s)] + [n for n in (lagged_note(e) for e in sc.sizes[s]) if n]
    made = sorted(str(e["run"]["attrs"]["created"]) for e in sc.sizes[s] if "created" in e["run"]["attrs"])
    loads = [float(e["run"]["attrs"]["load_average"]) for e in sc.sizes[s] if "load_average" in e["run"]["attrs"]]
    if made:
        notes.append(f"runs made {made[0]} – {made[-1]}" + (f", 1-min load at their start {min(loads):.2f}–{max(loads):.2f}"
                                                            if loads else "") + ".")
    return lines + [""] + [f"- {n}" for n in notes] + ([""] if notes else [])


def outer_cell(sc, s, o):
    """Each threshold's time of outer method o's fastest entry at size s, " / "-separated; the
    linear method once where one wins every threshold."""
    es = [(t, sc.outer_first(s, o, t)) for t in sc.thresholds]
    if all(e is None for _, e in es):
        return ""
    tags = {tag(e) for t, e in es if e is not None and rules.verdict(e["run"], t)[0] is not None}
    if len(tags) <= 1:
        text = " / ".join(cell(e, t, False) for t, e in es)
        if len(set(text.split(" / "))) == 1 and text.startswith("—"):
            text = text.split(" / ")[0]
        return text + (f" ({tags.pop()})" if tags else "")
    return " / ".join(cell(e, t) for t, e in es)


def headline(scenes):
    """Per scene and size: each outer method at its best, its time to every threshold (the linear
    method in brackets)."""
    outers = list(dict.fromkeys(o for sc in scenes for o in sc.outers))
    labels = {o: next(sc.outer_label(o) for sc in scenes if o in sc.outers) for o in outers}
    ths = sorted({t for sc in scenes for t in sc.thresholds}, reverse=True)
    lines = [f"Each cell: s to a position error of {' / '.join(f'{t:g}' for t in ths)}.", "",
             "| scene, size (dual rows) | " + " | ".join(labels[o] for o in outers) + " |",
             "|---|" + "---|" * len(outers)]
    for sc in scenes:
        for s in sc.order:
            cells = [outer_cell(sc, s, o) if o in sc.outers else "" for o in outers]
            lines.append(row([f"{sc.name} {s} ({sc.rows(s)})"] + cells))
    return lines


RULES = ("Each entry (an outer method with a linear method and a forcing rule; EW: linear.forcing = "
         "eisenstat_walker) in its own process, reading its size's one reference (`--reference-file`, computed once "
         "per size): the position error is the distance to the "
         "backward-Euler solution of the substep, ‖x − x_ref‖_M / ‖x_ref − x̃‖_M. `time to e`: the wall time within "
         "the frame (the reference's time is not in it) at which the error first is at most e; — (v): never, v the "
         "smallest error the run reached; — (reference unconverged …): the reference did not converge in that substep, "
         "so there is nothing true to time against; — (reference not fine enough): the reference's own error "
         "estimate (its certificate, results/README.md) is above e/100, so a time to e would be a time to the "
         "reference's own error. Rules: plots/race_rules.py; spec: figures/race/race.toml.")


def summary(scenes, spec=None):
    lines = ["# The race on the truth: time to a position error", "", RULES, "",
             "## Each outer method at its best", "",
             "Time (s) to each position error of each outer method's fastest entry (its linear method in brackets).", ""]
    lines += [provenance(scenes), ""] + headline(scenes) + [""]
    pick = race_pick.section(scenes, spec or {})
    if pick:
        lines += ["## " + (spec["pick"].get("title", "Which to pick")), ""] + pick + [""]
    for sc in scenes:
        lines += [f"## {sc.name}", ""]
        for s in sc.order:
            lines += size_table(sc, s)
    return "\n".join(lines) + "\n"


def provenance(scenes):
    """When and under what load the runs were made, from their own attributes."""
    runs = [e["run"]["attrs"] for sc in scenes for es in sc.sizes.values() for e in es]
    made = sorted(str(a["created"]) for a in runs if "created" in a)
    loads = [float(a["load_average"]) for a in runs if "load_average" in a]
    cpus = sorted({str(a["cpu_count"]) for a in runs if "cpu_count" in a})
    if not made:
        return "Runs: none recorded."
    return (f"Runs made {made[0]} – {made[-1]}, {len(runs)} entries; 1-min load at their start "
            + (f"{min(loads):.2f}–{max(loads):.2f}" if loads else "unknown") + f" on {'/'.join(cpus) or '?'} CPUs.")


def write_readme(path, scenes):
    """Replaces the table between README_BEGIN and README_END in `path` with the headline."""
    with open(path) as fh:
        text = fh.read()
    if README_BEGIN not in text or README_END not in text:
        sys.exit(f"{path}: no race-table markers ({README_BEGIN} … {README_END})")
    head, rest = text.split(README_BEGIN, 1)
    _, tail = rest.split(README_END, 1)
    new = head + README_BEGIN + "\n" + provenance(scenes) + "\n\n" + "\n".join(headline(scenes)) + "\n" + README_END + tail
    with open(path + ".tmp", "w") as fh:
        fh.write(new)
    os.replace(path + ".tmp", path)
    print(f"wrote the race table into {path}")


def draw(data_dir, out, spec, readme=None, pick=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = [Scene(name, sizes, spec) for name, sizes in load_entries(data_dir).items()]
    refs = reference_passes(data_dir)
    for sc in scenes:
        sc.references = {size: a for (scene, size), a in refs.items() if scene == sc.name}
    if not scenes:
        print(f"race: no runs under {data_dir}", file=sys.stderr)
        return
    os.makedirs(out, exist_ok=True)
    for sc in scenes:
        draw_scene(plt, sc, out)
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write(summary(scenes, spec))
    race_scaling.write(plt, scenes, data_dir, out)
    for name in ("timings.tsv", "plan.txt"):
        src = os.path.join(os.path.dirname(os.path.abspath(data_dir)), name)
        if os.path.exists(src) and os.path.abspath(out) != os.path.dirname(os.path.abspath(data_dir)):
            shutil.copyfile(src, os.path.join(out, name))
    print(f"wrote {os.path.join(out, 'summary.md')}")
    if readme:
        write_readme(readme, scenes)
    if pick:
        race_pick.write(pick, scenes, spec, data_dir)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data")
    ap.add_argument("--out", default=os.path.join(here, "race"))
    ap.add_argument("--spec", default=os.path.join(os.path.dirname(here), "figures", "race", "race.toml"))
    ap.add_argument("--readme", default=None, help="a file with the race-table markers (README.md)")
    ap.add_argument("--pick", default=None, help="write the [pick] comparison as this generated page")
    args = ap.parse_args()
    with open(args.spec, "rb") as fh:
        spec = tomllib.load(fh)
    draw(args.data, args.out, spec, args.readme, args.pick)


if __name__ == "__main__":
    main()
