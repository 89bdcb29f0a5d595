"""The race's rules, in one place: figures/race.py runs by them and plots/race.py draws and
summarises by them, so the two cannot disagree about a run's form, target or verdict.

- A run *finished* if its status is ok or max_iterations and it took an outer iteration; any
  other status (breakdown, diverged, timeout, ...) or a process that left no run (a failure
  record, `failed`) did not.
- A method's form (`form_of`): of its fixed-forcing runs in both forms at the smallest size of a
  scene, the one with the lower wall time per outer iteration among those that finished or ran
  out of time (a timeout measured its pace too; a breakdown or divergence did not); `primal` if
  neither did. A variant (`variant_of` in the spec) takes its method's form and runs only that.
- The target of a size (`target`): the value exact CHOLMOD's finished run ends the frame at, for
  each metric it records; no target where exact CHOLMOD did not finish.
- A run's time to a target: the wall time within the frame at which the metric first comes within
  TARGET_SLACK of it.
- A method's best entry (`best`): the one that reaches the dual target first; among those that
  never do, the finished one with the lowest final residual, then the rest.
"""
import math

import numpy as np

FINISHED = ("ok", "max_iterations")
PACED = FINISHED + ("timeout",)  # statuses whose time per outer iteration chooses a form
FALLBACK_FORM = "primal"
TARGET_SLACK = 1.05  # "reaches" exact CHOLMOD's end-of-frame value: within 5 %
# Metrics of a run against wall time, each relative to its first value where the dataset is not
# already (relative_dual_residual and position_error are), when the run has them.
METRICS = ("relative_dual_residual", "position_error", "newton_residual")


def status(run):
    """A run's status; `failed` for a failure record (a process that wrote no run)."""
    if run is None:
        return "missing"
    return str(run["attrs"].get("status", "failed"))


def finished(run):
    return (run is not None and status(run) in FINISHED
            and float(run["attrs"].get("outer_iterations", 0)) > 0 and "data" in run)


def per_iteration(run):
    """Wall seconds per outer iteration; NaN for a run that took none."""
    if run is None:
        return math.nan
    n = float(run["attrs"].get("outer_iterations", 0))
    return float(run["attrs"]["wall_time"]) / n if n > 0 else math.nan


def choose_form(runs_by_form):
    """{form: run or None} of one method's fixed-forcing runs at the smallest size -> its form."""
    timing = {f: per_iteration(r) for f, r in runs_by_form.items()
              if r is not None and status(r) in PACED and math.isfinite(per_iteration(r))}
    return min(timing, key=timing.get) if timing else FALLBACK_FORM


def base_of(name, methods):
    """The method a variant belongs to (its spec's variant_of), or None."""
    return (methods or {}).get(name, {}).get("variant_of")


def form_of(name, methods, runs_by_form, forms):
    """Method `name`'s form: its base method's (in `forms`) for a variant, else choose_form."""
    base = base_of(name, methods)
    if base:
        return forms.get(base, FALLBACK_FORM)
    return choose_form(runs_by_form)


def series(run, metric):
    """(wall time, values) of a metric over the first substep of the frame; None if not recorded."""
    d = run.get("data", {}) if run else {}
    if metric not in d or "wall_time" not in d or len(d[metric]) == 0:
        return None
    m = np.ones(len(d["iteration"]), dtype=bool)
    if "frame" in d:
        m &= np.asarray(d["frame"]) == np.asarray(d["frame"])[0]
    if "substep" in d:
        m &= np.asarray(d["substep"]) == 0
    t = np.asarray(d["wall_time"], dtype=float)[m]
    v = np.asarray(d[metric], dtype=float)[m]
    if metric == "newton_residual" and len(v) and v[0] > 0:
        v = v / v[0]
    return t, v


def final_value(run, metric):
    s = series(run, metric)
    return float(s[1][-1]) if s is not None and len(s[1]) else math.nan


def target(exact_run, metric="relative_dual_residual"):
    """What exact CHOLMOD ends the frame at; NaN where it did not finish or did not record it."""
    return final_value(exact_run, metric) if finished(exact_run) else math.nan


def time_to(run, goal, metric="relative_dual_residual"):
    """Wall time within the frame at which `metric` first comes within TARGET_SLACK of `goal`."""
    s = series(run, metric) if math.isfinite(goal) else None
    if s is None:
        return math.nan
    hit = np.flatnonzero(s[1] <= goal * TARGET_SLACK)
    return float(s[0][hit[0]]) if len(hit) else math.nan


def best(runs, goal):
    """The best of one method's runs (its variants and forcing rules) against the dual target."""
    def key(r):
        tt = time_to(r, goal)
        return (math.isnan(tt), tt if math.isfinite(tt) else 0.0, not finished(r),
                final_value(r, "relative_dual_residual") if finished(r) else math.inf)
    return min(runs, key=key) if runs else None
