"""The race's rules, in one place: figures/race.py runs by them and plots/race.py draws and
summarises by them, so the two cannot disagree about a run's verdict.

- The truth: every run's `--reference`, the backward-Euler solution of each substep
  (results/README.md). The race judges the first substep of each run's first frame (every race
  scene has one substep per frame; ball_drop's runs start from a saved state, in contact).
- An entry is an outer method (XPBD, its variants, Newton) with a linear method and a forcing rule.
- A run's time to a position error e (`verdict`): the wall time within that substep (the run's own
  clock: the reference's time is not in it) at the first entry whose `position_error` is at most e.
  None where no entry is ("never": the summary gives the smallest error reached), where the run's
  reference did not converge in that substep (nothing true to time against:
  `xbruns.reference_verdict` says so, and why), where it is not certified to e — its error
  estimate above e/100, or no certificate ("reference not fine enough", `xbruns.reference_trusted`:
  a time would be a time to the reference's own error) — or where the run left no data (its
  process failed).
- The best of a set of entries (`best`): the one that reaches the smallest threshold first; among
  those that never do, the one that reaches the next threshold first, and so on; then the smallest
  error reached. An outer method's best at one threshold (`first_to`): its entry that reaches that
  threshold first, whatever its linear method.
- The anchor (`ANCHOR`): XPBD with exact CHOLMOD runs first at each size; its frame (its time per
  outer iteration times the frame's outer iterations) bounds every other entry's time budget.
"""
import math

import numpy as np

import xbruns

ANCHOR = ("xpbd", "cholmod")
METRIC = "position_error"
NEVER, UNCONVERGED, NO_DATA, NO_REFERENCE = "never", "reference unconverged", "no data", "no reference"
NOT_FINE, UNCERTIFIED = xbruns.NOT_FINE, "reference not certified"


def status(run):
    """A run's status; `failed` for a failure record (a process that wrote no run)."""
    if run is None:
        return "missing"
    return str(run["attrs"].get("status", "failed"))


def series(run, metric=METRIC):
    """(wall time, values) of a metric over the first substep of the run's first frame; None if
    not recorded."""
    d = run.get("data", {}) if run else {}
    if metric not in d or "wall_time" not in d or len(d[metric]) == 0:
        return None
    m = np.ones(len(d["iteration"]), dtype=bool)
    if "frame" in d:
        m &= np.asarray(d["frame"]) == np.asarray(d["frame"])[0]
    if "substep" in d:
        m &= np.asarray(d["substep"]) == np.asarray(d["substep"])[0]
    return np.asarray(d["wall_time"], dtype=float)[m], np.asarray(d[metric], dtype=float)[m]


def smallest_error(run):
    """The smallest position error the run reached in the judged substep (NaN: none recorded)."""
    s = series(run)
    return float(np.min(s[1])) if s is not None and len(s[1]) else math.nan


def verdict(run, threshold):
    """(seconds, why) of a run against one threshold: (t, "") where it reached it at t; (None,
    NEVER | UNCONVERGED | NOT_FINE | UNCERTIFIED | NO_DATA | NO_REFERENCE) where it did not, or
    where nothing can say."""
    d = run.get("data") if run else None
    if not d or len(d.get("iteration", [])) == 0:
        return None, NO_DATA
    s = series(run)
    if s is None:
        return None, NO_REFERENCE
    converged, _ = xbruns.reference_verdict(run)
    if not converged:
        return None, UNCONVERGED
    trusted, why = xbruns.reference_trusted(run, threshold)
    if not trusted:
        return None, NOT_FINE if why.startswith(NOT_FINE) else UNCERTIFIED
    hit = np.flatnonzero(s[1] <= threshold)
    return (float(s[0][hit[0]]), "") if len(hit) else (None, NEVER)


def time_to(run, threshold):
    """Seconds to the threshold; NaN where `verdict` gives none."""
    t, _ = verdict(run, threshold)
    return math.nan if t is None else t


def rank_key(run, thresholds):
    """Sort key of a run by the rules of `best`: each threshold from the smallest, then the error."""
    key = []
    for e in sorted(thresholds):
        t = time_to(run, e)
        key += [math.isnan(t), 0.0 if math.isnan(t) else t]
    err = smallest_error(run)
    return tuple(key) + (math.isnan(err), 0.0 if math.isnan(err) else err)


def best(runs, thresholds):
    """The best of some runs (rules above); None for none."""
    runs = [r for r in runs if r is not None]
    return min(runs, key=lambda r: rank_key(r, thresholds)) if runs else None


def first_to(runs, threshold):
    """The run that reaches the threshold first, or None where none does."""
    timed = [(time_to(r, threshold), i) for i, r in enumerate(runs) if r is not None]
    timed = [(t, i) for t, i in timed if math.isfinite(t)]
    return runs[min(timed)[1]] if timed else None


def per_iteration(run):
    """Wall seconds per outer iteration; NaN for a run that took none."""
    if run is None:
        return math.nan
    n = float(run["attrs"].get("outer_iterations", 0))
    return float(run["attrs"]["wall_time"]) / n if n > 0 and "wall_time" in run["attrs"] else math.nan


def anchor_frame(run, frame_iterations):
    """The anchor's frame in seconds: its time per outer iteration times the frame's outer
    iterations; None where it took none (a failed anchor sets no bound)."""
    t = per_iteration(run)
    return None if math.isnan(t) else t * frame_iterations
