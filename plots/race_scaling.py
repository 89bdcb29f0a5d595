"""The scaling race's figure and results page, from the race's data (plots/race.py calls it).

- OUT/scaling_<scene>.png (and .pdf), for a scene with two sizes or more: the time to each position
  error threshold against the dual rows (the tets of a tet mesh), log-log, one line per (outer,
  linear) pair at its best forcing rule, its fitted slope and R² in the legend (and printed); beside
  them the peak memory of every entry against the rows.
- OUT/scale.md: when and on what the runs were made (cores, the triad bandwidth and load the race
  recorded in DATA/../machine.json, the load at each entry's start), the command that reproduces
  them, and per scene: which pair wins at each size and threshold and by how much, where the winner
  changes (the crossover sizes), the fitted slopes, what the data says against the paper's claims,
  and what the plan skipped or cut (DATA/../plan.json), with why.
The rules (time to e, trusted references, the best entry) are plots/race_rules.py's.
"""
import json
import math
import os

import numpy as np

import race_rules as rules
import xbruns

COMMAND = "make race-scale RACE_ARGS=\"--quiet\"   # resumable; then python3 plots/race.py plots/race/data --out docs/race --readme README.md"
LARGE = 2e5  # rows from which the paper expects the AMG to win


def peak_memory(run):
    v = run["attrs"].get("peak_memory")
    return float(v) if v not in (None, "") else math.nan


def series(sc, pair, threshold):
    """[(rows, seconds)] of a pair at its best entry per size, where it reached the threshold."""
    out = []
    for s in sc.order:
        e = sc.pair_best(s).get(pair)
        t = None if e is None else rules.verdict(e["run"], threshold)[0]
        if t is not None and t > 0:
            out.append((sc.rows(s), t))
    return out


def loglog(points):
    """(slope, R²) of log t against log rows; None below two sizes."""
    if len({n for n, _ in points}) < 2:
        return None
    a, _, r2 = xbruns.linear_fit(np.log([p[0] for p in points]), np.log([p[1] for p in points]))
    return a, r2


def pairs(sc):
    every = {p for s in sc.order for p in sc.pair_best(s)}
    return [(o, m) for o in sc.outers for m in sc.linears if (o, m) in every]


def pair_name(sc, pair):
    return f"{sc.outer_label(pair[0])} + {pair[1]}"


def fits_of(sc):
    """(pair, threshold, slope, R², sizes) of every pair and threshold with two sizes or more."""
    out = []
    for p in pairs(sc):
        for t in sc.thresholds:
            pts = series(sc, p, t)
            f = loglog(pts)
            if f:
                out.append((p, t, f[0], f[1], len(pts)))
    return out


def ratio_table(sc, num=("newton", "mgpbd"), den=("newton", "cholmod")):
    """Per size, num's time to each threshold over den's; den not reaching it (over its budget,
    skipped) counts as num's win."""
    if not any(num in sc.pair_best(s) for s in sc.order):
        return []
    head = ["size (rows)"] + [f"{pair_name(sc, num)} / {pair_name(sc, den)} to {t:g}" for t in sc.thresholds]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for s in sc.order:
        cells = [f"{s} ({sc.rows(s)})"]
        for t in sc.thresholds:
            a, b = time_of(sc, s, num, t), time_of(sc, s, den, t)
            e = sc.pair_best(s).get(den)
            why = rules.status(e["run"]) if e else "not run"
            cells.append("—" if a is None else (f"{a:.2f} / {b:.2f} = {a / b:.2f}" if b else f"{a:.2f} / — ({why})"))
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def draw(plt, sc, out):
    """The figure of one scene; returns the fitted (pair, threshold, slope, r², sizes) rows."""
    fits = fits_of(sc)
    slope = {(p, t): (a, r2) for p, t, a, r2, _ in fits}
    colours = {p: c for p, c in zip(pairs(sc), [plt.cm.tab20(i % 20) for i in range(40)])}
    fig, axes = plt.subplots(1, len(sc.thresholds) + 1, figsize=(5.2 * (len(sc.thresholds) + 1), 4.6),
                             squeeze=False, constrained_layout=True)
    for ax, t in zip(axes[0], sc.thresholds):
        for p in pairs(sc):
            pts = series(sc, p, t)
            if not pts:
                continue
            f = slope.get((p, t))
            label = pair_name(sc, p) + (f" (slope {f[0]:.2f}, R² {f[1]:.3f})" if f else "")
            ax.loglog([q[0] for q in pts], [q[1] for q in pts], "o-", color=colours[p], ms=4, lw=1.2, label=label)
        ax.set_title(f"{sc.name}: time to position error {t:g}", fontsize=9)
        ax.set_xlabel("dual rows (tets)")
        ax.set_ylabel("s within the frame")
        ax.grid(True, which="both", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6)
    ax = axes[0][-1]
    for p in pairs(sc):
        pts = [(sc.rows(s), peak_memory(e["run"])) for s in sc.order
               for (o, m), e in sc.pair_best(s).items() if (o, m) == p]
        pts = [q for q in pts if q[1] == q[1]]
        if pts:
            ax.loglog([q[0] for q in pts], [q[1] / 1e9 for q in pts], "s-", color=colours[p], ms=4, lw=1,
                      label=pair_name(sc, p))
    ax.set_title(f"{sc.name}: peak memory per entry", fontsize=9)
    ax.set_xlabel("dual rows (tets)")
    ax.set_ylabel("GB (peak resident set)")
    ax.grid(True, which="both", alpha=0.3)
    xbruns.save(fig, os.path.join(out, f"scaling_{sc.name}.png"))
    plt.close(fig)
    for p, t, a, r2, n in fits:
        print(f"scaling {sc.name}: {pair_name(sc, p)} to {t:g}: slope {a:.3f}, R² {r2:.4f} over {n} sizes")
    return fits


def ranking(sc, s, threshold):
    """[(seconds, pair)] of the pairs that reached the threshold at size s, fastest first."""
    out = []
    for p, e in sc.pair_best(s).items():
        t = rules.verdict(e["run"], threshold)[0]
        if t is not None:
            out.append((t, p))
    return sorted(out)


def winners_table(sc):
    head = ["size (rows)"] + [f"to {t:g}: winner, s (runner-up ×)" for t in sc.thresholds]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for s in sc.order:
        cells = [f"{s} ({sc.rows(s)})"]
        for t in sc.thresholds:
            r = ranking(sc, s, t)
            if not r:
                cells.append("none reached it")
            elif len(r) == 1:
                cells.append(f"{pair_name(sc, r[0][1])} {r[0][0]:.2f}")
            else:
                cells.append(f"{pair_name(sc, r[0][1])} {r[0][0]:.2f} ({pair_name(sc, r[1][1])} ×{r[1][0] / r[0][0]:.2f})")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def crossovers(sc):
    """Where the winner at a threshold changes from one size to the next."""
    out = []
    for t in sc.thresholds:
        prev = None
        for s in sc.order:
            r = ranking(sc, s, t)
            w = r[0][1] if r else None
            if prev and w and w != prev[1]:
                out.append(f"to {t:g}: {pair_name(sc, w)} overtakes {pair_name(sc, prev[1])} between {prev[0]} and {s}")
            if w:
                prev = (s, w)
    return out


def time_of(sc, s, pair, t):
    e = sc.pair_best(s).get(pair)
    return None if e is None else rules.verdict(e["run"], t)[0]


def against_paper(sc, fits):
    """The paper's expectations (an AMG solver wins at scale, its time is linear in the size, its
    lead over the direct solver grows) read against this scene's data."""
    out = []
    for s in sc.order:
        if sc.rows(s) < LARGE:
            continue
        for t in sc.thresholds:
            r = ranking(sc, s, t)
            if r and r[0][1][1] != "mgpbd":
                out.append(f"at {s} the fastest to {t:g} is {pair_name(sc, r[0][1])} ({r[0][0]:.2f} s), not an mgpbd "
                           "pair: against the paper's AMG winning at scale")
    for p, t, a, r2, n in fits:
        if p[1] == "mgpbd" and a > 1.1:
            out.append(f"{pair_name(sc, p)}'s time to {t:g} grows as rows^{a:.2f} (R² {r2:.3f}, {n} sizes): not "
                       "linear, as the paper's per-iteration fit (R² 0.998) would suggest for the time to the truth")
    for o in sc.outers:
        for t in sc.thresholds:
            ratios = [(s, time_of(sc, s, (o, "mgpbd"), t), time_of(sc, s, (o, "cholmod"), t)) for s in sc.order]
            ratios = [(s, a / b) for s, a, b in ratios if a and b]
            if len(ratios) >= 2 and ratios[-1][1] > ratios[0][1]:
                out.append(f"{sc.outer_label(o)}: mgpbd's time to {t:g} over exact CHOLMOD's grows from "
                           f"{ratios[0][1]:.2f} ({ratios[0][0]}) to {ratios[-1][1]:.2f} ({ratios[-1][0]}): its lead "
                           "shrinks with the size")
    return out


def stamp(scenes, machine):
    runs = [e["run"]["attrs"] for sc in scenes for es in sc.sizes.values() for e in es]
    made = sorted(str(a["created"]) for a in runs if "created" in a)
    loads = [float(a["load_average"]) for a in runs if "load_average" in a]
    cpus = sorted({str(a["cpu_count"]) for a in runs if "cpu_count" in a})
    hosts = sorted({str(a["machine"]) for a in runs if "machine" in a})
    triads = [m.get("triad_gb_s") for m in machine if m.get("triad_gb_s")]
    lines = [f"- Runs made {made[0]} – {made[-1]}, {len(runs)} entries." if made else "- No runs recorded.",
             f"- Machine: {'; '.join(hosts) or 'unknown'} ({'/'.join(cpus) or '?'} CPUs); triad "
             + ((f"{min(triads):.1f}" + (f"–{max(triads):.1f}" if max(triads) > min(triads) + 0.05 else "") + " GB/s")
                if triads else "not measured")
             + " (at the start of each part of the race).",
             "- 1-min load at each entry's start: " + (f"{min(loads):.2f}–{max(loads):.2f}" if loads else "unknown")
             + " (each entry's own in the summary).",
             f"- Reproduce: `{COMMAND}`."]
    return lines


def page(scenes, machine, plan):
    lines = ["# The scaling race: time to the truth against the size", "",
             "Generated by plots/race.py from the race's data (do not edit by hand).", ""]
    lines += stamp(scenes, machine) + [""]
    for sc in scenes:
        if len(sc.order) < 2 and not any(sc.rows(s) >= LARGE for s in sc.order):
            continue
        lines += [f"## {sc.name}", "", f"![time to the truth against the size](scaling_{sc.name}.png)", ""]
        lines += winners_table(sc) + [""]
        fits = fits_of(sc)
        lines += ratio_table(sc) + [""]
        if fits:
            lines += ["Fitted time to e ∝ rows^slope (log-log least squares over the sizes that reached e):", "",
                      "| pair | e | slope | R² | sizes |", "|---|---|---|---|---|"]
            lines += [f"| {pair_name(sc, p)} | {t:g} | {a:.2f} | {r2:.3f} | {n} |" for p, t, a, r2, n in fits]
            lines.append("")
        cross = crossovers(sc)
        lines += ["Crossovers: " + ("; ".join(cross) if cross else "none (one winner at every size)") + ".", ""]
        paper = against_paper(sc, fits)
        lines += ["Against the paper:" if paper else "Against the paper: nothing in this scene's data contradicts it.", ""]
        lines += [f"- {x}" for x in paper] + ([""] if paper else [])
    skipped = [p for p in plan if p["action"].startswith(("skip", "cut"))]
    if skipped:
        lines += ["## Not run", "", "| scene | size | entry | why |", "|---|---|---|---|"]
        lines += [f"| {p['scene']} | {p['size']} | {p['outer']} + {p['linear']} | {p['action']} |" for p in skipped]
        lines.append("")
    return "\n".join(lines) + "\n"


def read_json(path, default):
    try:
        with open(path) as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return default


def write(plt, scenes, data_dir, out):
    """The figures and scale.md (see the module's docstring)."""
    race_dir = os.path.dirname(os.path.abspath(data_dir))
    for sc in scenes:
        if len(sc.order) >= 2:
            draw(plt, sc, out)
    text = page(scenes, read_json(os.path.join(race_dir, "machine.json"), []), read_json(os.path.join(race_dir, "plan.json"), []))
    with open(os.path.join(out, "scale.md"), "w") as fh:
        fh.write(text)
    print(f"wrote {os.path.join(out, 'scale.md')}")
