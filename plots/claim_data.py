"""What the claim scripts (claims.py, profile_claims.py) share: the datasets they read, loading a
sweep's results, selecting runs and formatting table cells."""
import math
import os

import numpy as np

import xbruns

DATA = ("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "wall_time", "energy",
        "linear_iterations", "linear_relative_residual", "position_error")


def runs_of(path, **kw):
    return xbruns.load(path, **kw) if path and os.path.exists(path) else []


def matching(runs, **match):
    """The runs whose attributes equal every key=value given."""
    return [r for r in runs if all(str(r["attrs"].get(k)) == str(v) for k, v in match.items())]


def fmt(v, digits=3):
    """A table cell: — for none/NaN, integers as integers, else `digits` significant digits."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if isinstance(v, (int, np.integer)) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e6):
        return str(int(v))
    return f"{v:.{digits}g}"


def last_substep(run):
    d = run["data"]
    return int(d["frame"][-1]), int(d["substep"][-1])


def failed(run):
    return run["attrs"].get("status") in ("error", "nan", "breakdown", "diverged")
