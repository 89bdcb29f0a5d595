"""Shared reading and saving for the plots/ scripts (schema: results/README.md).

Every simulation run under /runs/<name> has attributes (scene, solver, status, outer_iterations,
final_dual_residual, relative_dual_residual, wall_time, rows, every parameter by key, and for
sweeps sweep_params/sweep_point/sweep_key) and per-entry datasets (frame, substep, iteration,
dual_residual, relative_dual_residual, wall_time, energy, position_error with a reference, ...).
"""
import json
import math
import os
import sys
import urllib.parse

import h5py
import numpy as np

# over_budget was called timeout before (older files); out_of_memory: past run --memory-limit.
STATUS_ORDER = ["ok", "max_iterations", "over_budget", "timeout", "out_of_memory", "diverged", "nan", "breakdown",
                "error"]
STATUS_COLOURS = {"ok": "#4caf50", "max_iterations": "#ffc107", "over_budget": "#ff9800", "timeout": "#ff9800",
                  "out_of_memory": "#6d4c41", "diverged": "#e53935", "nan": "#8e0000", "breakdown": "#8e24aa",
                  "error": "#757575"}


def _text(v):
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v


SCHEMA_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "results", "schema.json")


def schema():
    """results/schema.json: the names, levels and types of every attribute and dataset a run may
    hold (the list the recorder writes by, harness/io/schema.cpp)."""
    with open(SCHEMA_PATH) as fh:
        return json.load(fh)


def dataset_names(level="simulation"):
    return {d["name"] for d in schema()["datasets"] if d["level"] in ("any", level)}


def _link_target(index, filename):
    """Where an external link of the index at `index` (a real path) points, as the harness resolves
    it (results/README.md): "<x>.runs/<rest>" is in INDEX.runs/, another relative name beside the
    index; never the working directory."""
    if os.path.isabs(filename):
        return filename
    first, _, rest = filename.replace(os.sep, "/").partition("/")
    if first.endswith(".runs") and len(first) > 5:
        return os.path.join(index + ".runs", rest)
    return os.path.join(os.path.dirname(index), filename)


def _one_line(e):
    text = str(e).strip().splitlines()
    return text[0] if text else type(e).__name__


def run_groups(path, skipped):
    """(name, h5py group) of every run of a results file, as `report` and xpbd_bench.read read it:
    the run files of its store (PATH.runs/<store>/, whatever the file is called now), or the runs
    the file holds or links itself (a packed or older file). Each run file is open only while its
    run is in hand. A run that cannot be read is named in `skipped` ("PATH: run NAME: why") and left
    out. Exits with one line for a file that is missing, not HDF5 or without /runs."""
    if not os.path.exists(path):
        sys.exit(f"{path}: no such file")
    real = os.path.realpath(path)
    try:
        f = h5py.File(real, "r")
    except OSError as e:
        sys.exit(f"{path}: not a readable HDF5 file ({_one_line(e)})")
    with f:
        if "runs" not in f or not isinstance(f.get("runs", getlink=False), h5py.Group):
            sys.exit(f"{path}: no /runs group (not an xpbd-bench results file?)")
        store = _text(f.attrs.get("store", ""))
        listed = sorted(f["runs"])
        if store:
            yield from _stored_runs(path, real, store, _text(f.attrs.get("links_to", "")), listed, skipped)
            return
        for name in listed:
            link = f["runs"].get(name, getlink=True)
            try:
                if isinstance(link, h5py.ExternalLink):
                    with h5py.File(_link_target(real, link.filename), "r") as rf:
                        g = rf[link.path]
                        if not isinstance(g, h5py.Group):
                            raise TypeError("not a run group")
                        yield name, g
                    continue
                g = f["runs"][name]
                if not isinstance(g, h5py.Group):
                    raise TypeError("not a run group")
            except (OSError, KeyError, TypeError, ValueError) as e:
                skipped.append(f"{path}: run {name}: {_one_line(e)}")
                continue
            yield name, g


def _stored_runs(path, real, store, links_to, listed, skipped):
    folder = os.path.join(real + ".runs", store)
    if not os.path.isdir(folder) and links_to and not os.path.isabs(links_to):
        linked = os.path.join(os.path.dirname(real), links_to)  # renamed without its folder: the one its links name
        folder = linked if os.path.isdir(linked) else folder
    if not os.path.isdir(folder):
        skipped.append(f"{path}: its runs folder {path}.runs/{store} is missing (moved, renamed or not copied with it?)")
        return
    seen = set()
    for fn in sorted(os.listdir(folder)):
        if fn.startswith(".") or not fn.endswith(".h5"):
            continue
        seen.add(urllib.parse.unquote(fn[:-3].split(".")[0]))  # NNNN_<name>[.k<job>].h5, its name %XX-quoted
        try:
            with h5py.File(os.path.join(folder, fn), "r") as rf:
                (name, g), = rf["runs"].items()
                seen.add(name)
                yield name, g
        except (OSError, KeyError, TypeError, ValueError) as e:
            skipped.append(f"{path}: run file {fn}: {_one_line(e)}")
    for name in listed:
        if name not in seen:
            skipped.append(f"{path}: run {name} is listed by the index but its run file is gone from {folder}")


def load(path, datasets=("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "wall_time"),
         level="simulation"):
    """A list of runs, by name: dict(name, attrs, data) with the requested datasets that exist. A
    dataset the schema does not list for the level is a programming error in the plot, not missing
    data. A run that cannot be read is named on stderr, one line each, and left out."""
    known = dataset_names(level) if level else {d["name"] for d in schema()["datasets"]}
    unknown = [d for d in datasets if d not in known]
    if unknown:
        raise ValueError(f"xbruns.load: {', '.join(unknown)} not in results/schema.json for {level or 'any'} runs")
    runs, skipped = [], []
    for name, g in run_groups(path, skipped):
        try:
            attrs = {k: _text(v) for k, v in g.attrs.items()}
            if level and attrs.get("level", "simulation") != level:
                continue
            data = {}
            for d in datasets:
                if d in g:
                    a = g[d][()]
                    if a.dtype.kind in "OS":
                        a = np.array([_text(x) for x in a])
                    data[d] = a
        except (OSError, KeyError, TypeError, ValueError) as e:
            skipped.append(f"{path}: run {name}: {_one_line(e)}")
            continue
        runs.append(dict(name=name, attrs=attrs, data=data))
    for s in skipped:
        print(f"{os.path.basename(sys.argv[0]) or 'plots'}: skipped: {s}", file=sys.stderr)
    return sorted(runs, key=lambda r: r["name"])


# The reference's records (results/README.md, run --reference): what a plot needs to judge it.
REFERENCE_DATASETS = ("reference/status", "reference/success", "reference/relative_energy_gradient",
                      "reference/relative_dual_residual", "reference/error_estimate", "reference/certified",
                      "reference/certified_threshold", "reference/certificate_note")
NOT_FINE = "reference not fine enough"


def reference_verdict(run, index=0):
    """Whether the run's reference converged in substep `index` of the run (0: its first), the
    one place the plots read that: (True, "") or (False, why), e.g. "stagnated at ‖∇E‖ 0.00025 of
    its start". It reads the success predicate the harness wrote (reference/success), never the
    status names. Needs REFERENCE_DATASETS loaded; a run without them has no verdict (False)."""
    d = run.get("data", {}) if run else {}
    st, ok = d.get("reference/status"), d.get("reference/success")
    if st is None or len(st) <= index:
        return False, "no reference recorded"
    if ok is None or len(ok) <= index:
        return False, "no reference/success recorded (a file from before it)"
    if int(ok[index]):
        return True, ""
    why = str(st[index])
    g = d.get("reference/relative_energy_gradient")
    if g is not None and len(g) > index:
        why += f" at ‖∇E‖ {float(g[index]):.2g} of its start"
    return False, why


def reference_trusted(run, threshold, index=0):
    """Whether the run's reference in substep `index` may judge a position error of `threshold`:
    (True, "") where it is certified and its error estimate is at most threshold/100 (the harness
    records that bound as reference/certified_threshold, harness/sim/reference.hpp), else (False,
    why): why starts with NOT_FINE where the reference is certified but not to that threshold.
    Every script that prints a position error against a threshold asks this first."""
    ok, why = reference_verdict(run, index)
    if not ok:
        return False, "reference unconverged: " + why if why != "no reference recorded" else why
    d = run.get("data", {})
    th, cert = d.get("reference/certified_threshold"), d.get("reference/certified")
    if th is None or cert is None or len(th) <= index:
        return False, "reference not certified (a file from before the certificate)"
    if not int(cert[index]):
        note = d.get("reference/certificate_note")
        return False, "reference not certified" + (f": {note[index]}" if note is not None and len(note) > index and
                                                   str(note[index]) else "")
    if float(th[index]) <= threshold:
        return True, ""
    est = d.get("reference/error_estimate")
    return False, NOT_FINE + (f" (its error estimate {float(est[index]):.2g} > {threshold:g}/100)" if est is not None else "")


def error_text(value, attrs, digits=3):
    """A run's position error as its references allow it to be printed (the run's attributes, whose
    reference_certified_threshold is the finest error every substep's reference can judge, 100
    times its worst error estimate): the value where the references vouch for it, else NOT_FINE
    (or why there is no reference to judge by). For scripts that print a run's error."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if "reference_substeps_unconverged" not in attrs:
        return f"{value:.{digits}g} (no reference)"
    if int(attrs["reference_substeps_unconverged"]):
        return f"{value:.{digits}g} (reference unconverged)"
    th = float(attrs.get("reference_certified_threshold", math.inf))
    if not th <= value:
        return f"{NOT_FINE} (it judges ≥ {th:.2g})" if math.isfinite(th) else "reference not certified"
    return f"{value:.{digits}g}"


def substep_index(run, frame, substep):
    """The index into the run's per-substep datasets (reference/..., substep_status) of a frame's
    substep: substeps are recorded in order, one per iteration-0 entry."""
    d = run["data"]
    it, fr, sb = (np.asarray(d[k]) for k in ("iteration", "frame", "substep"))
    starts = np.flatnonzero(it == 0)
    hit = np.flatnonzero((fr[starts] == frame) & (sb[starts] == substep))
    return int(hit[0]) if len(hit) else None


METRICS = ("true", "authors")


def residual_key(metric="true", relative=False):
    """The dataset of a residual metric (results/README.md): true = dual_residual, authors =
    authors_dual_residual (what the MGPBD authors' code logs); relative_ prefixed if relative."""
    if metric not in METRICS:
        raise ValueError(f"unknown residual metric {metric!r} (valid: {', '.join(METRICS)})")
    base = "dual_residual" if metric == "true" else "authors_dual_residual"
    if relative:
        return "relative_dual_residual" if metric == "true" else "authors_relative_dual_residual"
    return base


def cumulative_time(run):
    """Wall time running over the whole run (each substep's clock restarts at 0)."""
    wt = np.asarray(run["data"]["wall_time"], dtype=float)
    it = np.asarray(run["data"]["iteration"])
    cum = wt.copy()
    offset = 0.0
    starts = list(np.flatnonzero(it == 0)) + [len(wt)]
    for s, e in zip(starts[:-1], starts[1:]):
        cum[s:e] = wt[s:e] + offset
        offset = cum[e - 1] if e > s else offset
    return cum


def substep_mask(run, frame=None, substep=None):
    d = run["data"]
    m = np.ones(len(d["iteration"]), dtype=bool)
    if frame is not None:
        m &= np.asarray(d["frame"]) == frame
    if substep is not None:
        m &= np.asarray(d["substep"]) == substep
    return m


def own_key(run):
    """The relative dataset of the measure the run's stop test read (attribute convergence_measure):
    relative_newton_residual for energy_gradient (‖∇E‖ over its value at x̃: Newton, vbd, avbd),
    else the relative dual residual it names (the true one for runs from before the attribute)."""
    m = str(run["attrs"].get("convergence_measure", "dual_residual"))
    return {"energy_gradient": "relative_newton_residual",
            "authors_dual_residual": "authors_relative_dual_residual"}.get(m, "relative_dual_residual")


def to_tolerance(run, tol, frame=0, substep=0, metric="true", after_first=False):
    """(outer iterations, seconds) until the relative residual of `metric` (true, authors, or own:
    the run's own stop measure, own_key) is <= tol in one substep; NaNs if never (or if the run has
    no such dataset). after_first: seconds counted from the end of outer iteration 1, i.e. without
    the setup and the first iteration (the authors' timing)."""
    d = run["data"]
    key = own_key(run) if metric == "own" else residual_key(metric, relative=True)
    if key not in d:
        return math.nan, math.nan
    m = substep_mask(run, frame, substep)
    rel = np.asarray(d[key])[m]
    t = np.asarray(d["wall_time"], dtype=float)[m]
    it = np.asarray(d["iteration"])[m]
    hit = np.flatnonzero(rel <= tol)
    if len(hit) == 0:
        return math.nan, math.nan
    start = t[np.flatnonzero(it >= 1)[0]] if after_first and np.any(it >= 1) else 0.0
    return float(it[hit[0]]), float(t[hit[0]] - start)


def value_at_iteration(run, key, iteration, frame=0, substep=0):
    """A dataset's value at an outer iteration of one substep (the last one if it stopped earlier)."""
    d = run["data"]
    m = substep_mask(run, frame, substep)
    v = np.asarray(d[key])[m]
    it = np.asarray(d["iteration"])[m]
    if len(v) == 0:
        return math.nan
    k = np.flatnonzero(it <= iteration)
    return float(v[k[-1]]) if len(k) else math.nan


def as_number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def swept(run):
    """The run's swept keys (sweep_params) and their values, in order."""
    keys = [k for k in str(run["attrs"].get("sweep_params", "")).split(",") if k]
    return {k: run["attrs"].get(k) for k in keys}


def label(run, keys=None):
    a = run["attrs"]
    s = str(a.get("solver", "?"))
    keys = keys if keys is not None else list(swept(run))
    extra = " ".join(f"{k}={fmt(a.get(k))}" for k in keys)
    return f"{s} {extra}".strip()


def fmt(v):
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def default_out(results, suffix):
    base = os.path.splitext(results)[0]
    return f"{base}_{suffix}.png"


def save(fig, out):
    """Writes OUT as PNG and the same figure as PDF beside it (write_figure: whole or not at all)."""
    root = os.path.splitext(out)[0]
    write_figure(fig, root + ".png", dpi=150, bbox_inches="tight")
    write_figure(fig, root + ".pdf", bbox_inches="tight")
    print(f"wrote {root}.png and {root}.pdf")


def write_figure(fig, path, **savefig_args):
    """fig.savefig to PATH through PATH.tmp, flushed to disk and renamed over PATH, as the harness
    writes its files (docs/failures.md). A failed write (a full disk) ends the script with one
    line naming the file and the cause and exit code 2; PATH is left as it was, no .tmp stays."""
    tmp = path + ".tmp"
    try:
        d = os.path.dirname(path)
        if d:
            os.makedirs(d, exist_ok=True)
        with open(tmp, "wb") as fh:
            fig.savefig(fh, format=os.path.splitext(path)[1][1:] or "png", **savefig_args)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as e:
        try:
            os.remove(tmp)
        except OSError:
            pass
        cause = os.strerror(e.errno) if e.errno else str(e)
        cause = cause[:1].lower() + cause[1:] if cause[1:2].islower() else cause
        print(f"{os.path.basename(sys.argv[0]) or 'plots'}: cannot write {path}: {cause} ({path} is left as it was)",
              file=sys.stderr)
        sys.exit(2)


def linear_fit(x, y):
    """Least-squares y = a x + b and R²."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    a, b = np.polyfit(x, y, 1)
    ss_res = float(np.sum((y - (a * x + b)) ** 2))
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    return float(a), float(b), r2


def cloth_strains(run):
    """(per-edge strain |p−q|/l0 − 1, per-vertex largest strain, positions) of a cloth run.

    Edges and rest lengths from the datasets distance_edges / distance_rest_length when the run
    has them, else the grid of problems/generators make_cloth_grid(N) (vertex (i, k) = i·(N+1)+k,
    edges along k, along i and one diagonal per quad) from the attributes resolution and size.
    """
    d = run["data"]
    x = np.asarray(d["final_positions"], dtype=float).reshape(-1, 3)
    if "distance_edges" in d and "distance_rest_length" in d:
        e = np.asarray(d["distance_edges"]).astype(int).reshape(-1, 2)
        l0 = np.asarray(d["distance_rest_length"], dtype=float)
    else:
        a = run["attrs"]
        n, size = int(a["resolution"]), float(a["size"])
        n1 = n + 1
        if x.shape[0] != n1 * n1:
            raise ValueError(f"{run['name']}: {x.shape[0]} positions, expected {n1 * n1} for a {n}x{n} cloth")
        idx = np.arange(n1 * n1).reshape(n1, n1)
        e = np.concatenate([np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], 1),
                            np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], 1),
                            np.stack([idx[:-1, :-1].ravel(), idx[1:, 1:].ravel()], 1)])
        k, i = np.meshgrid(np.arange(n1), np.arange(n1))
        rest = np.stack([size * k.ravel() / n, np.zeros(n1 * n1), size * i.ravel() / n], 1)
        l0 = np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)
    s = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / l0 - 1.0
    per_vertex = np.zeros(x.shape[0])
    np.maximum.at(per_vertex, e[:, 0], s)
    np.maximum.at(per_vertex, e[:, 1], s)
    return s, per_vertex, x
