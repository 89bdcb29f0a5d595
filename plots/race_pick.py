"""The race's "XPBD, VBD, Newton: which to pick" section (docs/vbd.md), from the race's own runs.

The spec's [pick] table names the entries to compare (outer and linear method, each at its best
forcing rule) and the position error they race to; per scene and size this writes which reaches it
first and by how much (the next one's time over the first's), or why none does. plots/race.py puts
it into OUT/summary.md, and with --pick FILE writes it as a generated page of its own
(docs/results/vbd_pick.md), so that the text is never typed by hand.
"""
import math
import os

import race_rules as rules
import xbruns

def _time(sc, s, outer, linear, threshold):
    """(seconds or None, why, entry) of the pair at its best forcing rule."""
    e = sc.pair_best(s).get((outer, linear))
    if e is None:
        return None, "not run", None
    t, why = rules.verdict(e["run"], threshold)
    if t is None and why == rules.NEVER:
        its = e["run"]["attrs"].get("outer_iterations", "?")
        why = f"never in {its} its; smallest error {xbruns.fmt(rules.smallest_error(e['run']))}"
    return t, why, e


def _cell(t, why):
    return f"{t:.2f}" if t is not None else f"— ({why})"


def _verdict(times, labels):
    """Who reaches the error first and by how much."""
    reached = sorted((t, l) for t, l in zip(times, labels) if t is not None)
    if not reached:
        return "none reaches it"
    first = f"{reached[0][1]} first ({reached[0][0]:.2f} s)"
    if len(reached) == 1:
        return first + ", the only one to reach it"
    t0, t1 = reached[0][0], reached[1][0]
    ratio = t1 / t0 if t0 > 0 else math.inf
    return first + f", {ratio:.1f}× before {reached[1][1]} ({t1:.2f} s)"


def section(scenes, spec):
    """Markdown lines of the section; [] without a [pick] table in the spec."""
    pick = spec.get("pick")
    if not pick:
        return []
    threshold = float(pick.get("threshold", 1e-2))
    entries = pick.get("entries", [])
    labels = [p.get("label", f"{p['outer']} + {p['linear']}") for p in entries]
    runs = [e["run"]["attrs"] for sc in scenes for es in sc.sizes.values() for e in es]
    loads = [float(a["load_average"]) for a in runs if "load_average" in a]
    made = sorted(str(a["created"]) for a in runs if "created" in a)
    lines = [f"Time (s) within the frame to a position error of {threshold:g} against the backward-Euler solution "
             "(the race's rules: docs/race.md), each entry at its best forcing rule; — (why): never within its "
             "run, or nothing to time against.", ""]
    cpus = sorted({int(float(a["cpu_count"])) for a in runs if "cpu_count" in a})
    if made:
        busy = loads and cpus and max(loads) > min(cpus)
        lines += [f"Race runs made {made[0]} – {made[-1]}; 1-min load at their start "
                  + (f"{min(loads):.2f}–{max(loads):.2f}" if loads else "unknown") + f" on {'/'.join(map(str, cpus)) or '?'} CPUs"
                  + (": a busy machine, whose times are not a quiet one's (fewer sweeps fit a budget)." if busy else "."), ""]
    lines += ["| scene, size | " + " | ".join(labels) + " | which first, by how much |",
              "|---|" + "---|" * (len(labels) + 1)]
    for sc in scenes:
        for s in sc.order:
            got = [_time(sc, s, p["outer"], p["linear"], threshold) for p in entries]
            if all(e is None for _, _, e in got):
                continue
            cells = [_cell(t, why) for t, why, _ in got]
            lines.append("| " + " | ".join([f"{sc.name} {s}"] + cells + [_verdict([t for t, _, _ in got], labels)]) + " |")
    return lines


def write(path, scenes, spec, data_dir):
    """The section as a generated page of its own (pages.py's marker first: not hand-written docs)."""
    import pages
    title = spec.get("pick", {}).get("title", "Which to pick")
    body = section(scenes, spec) or ["(the spec has no [pick] table)"]
    cmd = f"python3 plots/race.py {os.path.relpath(data_dir)} --pick {os.path.relpath(path)}"
    text = "\n".join([pages.marker("plots/race.py", os.path.relpath(data_dir)), f"# {title}", "",
                      "From the race's runs (`make race`, or the part of it these entries need: `python3 figures/race.py "
                      "--quick --only cloth_hang,squash --outer xpbd,vbd,avbd,newton --linear "
                      "xpbd-gs,vbd,vbd-chebyshev,avbd,mgpbd`; the comparison: figures/race/race.toml's [pick]); this "
                      f"page: `{cmd}`. A sweep entry runs until its time budget (docs/race.md).", ""] + body) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path + ".tmp", "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(path + ".tmp", path)
    print(f"wrote {path}")
