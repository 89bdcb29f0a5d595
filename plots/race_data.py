"""The race's runs as the plots read them: one file per entry under DATA_DIR/<scene>/<size>/, a
failure record where a process left none, the size's reference pass (plots/race.py, figures/race.py).
"""
import json
import os
import re

import race_rules as rules
import xbruns

DATASETS = ("frame", "substep", "iteration", "wall_time", "relative_dual_residual", "linear_iterations",
            rules.METRIC, "reference/source") + xbruns.REFERENCE_DATASETS


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
