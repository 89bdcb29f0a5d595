"""The plan of a race (figures/race.py): what each entry is predicted to take, what it may take, and
what is not run, and why.

- Prediction: an entry's process seconds and peak memory at a size, from the same entry (outer,
  linear, forcing) at the smaller sizes of the same scene already run (OUT/timings.tsv): a power
  law in the size (rows of the dual system: the tets of a tet mesh), fitted through two or more of
  them (the slope clipped to [0.5, 3]), else through the one with the spec's default slope; where
  none has run, the spec's `[plan.prior]` per linear method. Every prediction says which it is.
- Budget: `plan.budget_factor` × the predicted seconds, at least `plan.min_budget`, at most the
  spec's `time_budget` (an entry past it ends as over_budget, its log kept, and the race goes on).
- Memory: each entry runs under `--memory-limit` = `plan.memory_limit` GB, at most what the machine
  has available at its start less `plan.memory_reserve`; an entry predicted over it is skipped
  before it starts, as is one that ran out of memory at a smaller size (one over its budget there
  is predicted from that time, a lower bound).
- The campaign's time: entries are taken in priority order (`plan.priority`, "outer.linear"
  pairs, the rest after them in the spec's order; each size's reference first), smaller sizes
  first within a pair; an entry whose prediction would take the campaign past
  `plan.total_seconds` (the seconds already spent in OUT/timings.tsv counted) is cut.
The driver plans before it starts (--dry-run prints the plan and stops) and again before each
size, with what the sizes before it measured.
"""
import math
import os

import numpy as np

GB = 1e9
DONE_BAD = ("over_budget", "timeout", "out_of_memory")  # a larger size of the entry will not do better
REFERENCE = "_reference"  # the outer name of a size's reference pass


def read_timings(path):
    """{entry path relative to OUT: dict(seconds, code, load, status, peak, rows)}, the last line of
    each; the columns after the load (status, peak bytes, rows) are absent in older files."""
    out = {}
    if not os.path.exists(path):
        return out
    with open(path) as fh:
        for line in fh:
            f = line.rstrip("\n").split("\t")
            if len(f) < 5:
                continue
            extra = f[5:] + [""] * (3 - len(f[5:]))
            num = (lambda s: float(s) if s not in ("", "nan") else math.nan)
            out[f[1]] = dict(start=f[0], seconds=float(f[2]), code=f[3], load=float(f[4]), status=extra[0],
                             peak=num(extra[1]), rows=num(extra[2]))
    return out


def fit(points, default_slope):
    """(slope, log intercept, r², how) of log y = a + b log n through (n, y) points (n > 0, y > 0)."""
    pts = sorted((n, y) for n, y in points if n > 0 and y > 0)
    if not pts:
        return None
    if len({n for n, _ in pts}) < 2:
        n, y = pts[-1]
        return default_slope, math.log(y) - default_slope * math.log(n), math.nan, f"1 size, slope {default_slope:g}"
    x, v = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    b, a = np.polyfit(x, v, 1)
    r2 = 1 - np.sum((v - (a + b * x)) ** 2) / max(np.sum((v - v.mean()) ** 2), 1e-300)
    b = float(min(max(b, 0.5), 3.0))
    a = float(np.mean(v - b * x))
    return b, a, float(r2), f"{len(pts)} sizes, slope {b:.2f}"


def prior(spec, name, rows, iterations):
    """(seconds, bytes) from the spec's [plan.prior.<name>] (a linear method, or reference.<its
    linear method>): seconds per outer iteration and bytes per row at 1e5 rows, each with its
    exponent, and seconds to start (the mesh, the first setup)."""
    p = spec.get("plan", {}).get("prior", {})
    m = p.get(name, p.get("default", {}))
    s = m.get("seconds", 0.5) * (rows / 1e5) ** m.get("slope", 1.2) * iterations + m.get("start", 1.0)
    b = m.get("bytes", 4000) * 1e5 * (rows / 1e5) ** m.get("memory_slope", 1.0) + 0.15 * GB
    return s, b


class Entry:
    """One process of the race: a size's reference pass or an (outer, linear, forcing) entry."""

    def __init__(self, scene, size_index, size, outer, linear, forcing, rel):
        self.scene, self.size_index, self.size, self.rel = scene, size_index, size, rel
        self.outer, self.linear, self.forcing = outer, linear, forcing
        self.rows = float(size.get("rows", 0))
        self.done = False
        self.seconds = self.bytes = math.nan
        self.how = ""
        self.budget = math.nan
        self.action = "run"

    @property
    def key(self):
        return (self.scene, self.outer, self.linear, self.forcing)

    @property
    def pair(self):
        return f"{self.outer}.{self.linear}"

    def label(self):
        what = "reference" if self.outer == REFERENCE else f"{self.outer} + {self.linear} ({self.forcing})"
        return f"{self.scene} {self.size['label']}: {what}"


def history(entries, timings):
    """{key: [(rows, seconds, peak bytes, status, size label)]} of every finished entry."""
    out = {}
    for e in entries:
        t = timings.get(e.rel)
        if t and e.done:
            rows = t["rows"] if t["rows"] == t["rows"] else e.rows
            out.setdefault(e.key, []).append((rows, t["seconds"], t["peak"], t["status"], e.size["label"]))
    return out


def predict(spec, e, past, iterations):
    """Sets e.seconds, e.bytes, e.how (and e.action for a skip learnt at a smaller size);
    `iterations`: the outer iterations the entry is expected to take (for the prior). An entry
    that ran out of memory at a smaller size is skipped; one that ran over its budget there is a
    lower bound: its seconds with plan.slope, at least."""
    smaller = [p for p in past.get(e.key, []) if p[0] < e.rows]
    oom = [p for p in smaller if p[3] == "out_of_memory"]
    if oom:
        e.action = f"skip: out_of_memory at {oom[-1][4]}"
    plan = spec.get("plan", {})
    prior_s, prior_b = prior(spec, e.linear if e.outer != REFERENCE else f"reference.{e.linear}", e.rows, iterations)
    good = [p for p in smaller if p[3] not in DONE_BAD]
    f = fit([(p[0], p[1]) for p in good], plan.get("slope", 1.2))
    e.seconds, e.how = (prior_s, "prior") if f is None else (math.exp(f[1] + f[0] * math.log(e.rows)), f[3])
    late = [p for p in smaller if p[3] in ("over_budget", "timeout")]
    if late:
        bound = late[-1][1] * (e.rows / late[-1][0]) ** plan.get("slope", 1.2)
        if bound > e.seconds:
            e.seconds, e.how = bound, f"over its budget at {late[-1][4]}: at least"
    g = fit([(p[0], p[2]) for p in good if p[2] == p[2]], plan.get("memory_slope", 1.1))
    e.bytes = prior_b if g is None else math.exp(g[1] + g[0] * math.log(e.rows))


def budget(spec, e):
    plan = spec.get("plan", {})
    return min(spec["time_budget"], max(plan.get("min_budget", 10.0), plan.get("budget_factor", 3.0) * e.seconds))


def memory_limit(spec):
    """The GB an entry may use now: plan.memory_limit, at most MemAvailable less plan.memory_reserve."""
    plan = spec.get("plan", {})
    limit = float(plan.get("memory_limit", 0) or 1e9)
    try:
        with open("/proc/meminfo") as fh:
            avail = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("MemAvailable:"))
        limit = min(limit, avail / GB - float(plan.get("memory_reserve", 1.0)))
    except (OSError, StopIteration):
        pass
    return max(limit, 0.5)


def priority_of(spec, e):
    if e.outer == REFERENCE:
        return -1
    order = spec.get("plan", {}).get("priority", [])
    return order.index(e.pair) if e.pair in order else len(order)


def make_plan(spec, entries, timings, iterations, total=None, limit_gb=None):
    """Predicts, budgets and decides every entry (in place; `iterations(e)`: its expected outer
    iterations); returns (spent, planned) seconds."""
    past = history(entries, timings)
    limit_gb = memory_limit(spec) if limit_gb is None else limit_gb
    spent = sum(timings[e.rel]["seconds"] for e in entries if e.done and e.rel in timings)
    for e in entries:
        if e.done:
            e.action = "done"
            continue
        e.action = "run"
        predict(spec, e, past, iterations(e))
        e.budget = budget(spec, e)
        if e.action == "run" and e.bytes > limit_gb * GB:
            e.action = f"skip: predicted {e.bytes / GB:.1f} GB > the {limit_gb:.1f} GB limit"
        elif e.action == "run" and e.seconds > spec["time_budget"]:
            e.action = f"skip: predicted {e.seconds:.0f} s > the time budget {spec['time_budget']:g} s"
    planned = 0.0
    todo = [e for e in entries if e.action == "run"]
    refs_needed = {(e.scene, e.size_index) for e in todo if e.outer != REFERENCE}
    for e in sorted(todo, key=lambda e: (priority_of(spec, e), e.rows)):
        if e.outer == REFERENCE and (e.scene, e.size_index) not in refs_needed:
            e.action = "cut: no entry of this size runs"
            continue
        cost = min(e.seconds, e.budget)
        if total is not None and spent + planned + cost > total:
            e.action = f"cut: the campaign's {total:g} s ({spent:.0f} spent, {planned:.0f} planned before it)"
            continue
        planned += cost
    return spent, planned


def plan_text(entries, spent, planned, total, limit_gb):
    lines = [f"plan: {len(entries)} processes; memory limit {limit_gb:.1f} GB; spent {spent:.0f} s, planned "
             f"{planned:.0f} s" + (f" of {total:g} s" if total else "")]
    for e in entries:
        pred = "" if e.done else f"{e.seconds:8.1f} s {e.bytes / GB:6.2f} GB budget {e.budget:6.0f} s ({e.how})"
        lines.append(f"  {e.label():60s} {pred}  {e.action}")
    return "\n".join(lines)


def plan_records(entries):
    """What plots/race.py reads (OUT/plan.json): each entry's prediction and decision."""
    return [dict(scene=e.scene, size=e.size["label"], outer=e.outer, linear=e.linear, forcing=e.forcing,
                 rows=e.rows, seconds=None if e.done else e.seconds, bytes=None if e.done else e.bytes,
                 how=e.how, budget=None if e.done else e.budget, action=e.action) for e in entries]
