#!/usr/bin/env python3
"""`make figures`: run the sweep specs under figures/ and reproduce the paper's claims.

usage: python3 plots/figures.py [--bench build/xpbd-bench] [--size default|paper] [--only a,b]
                                [--out plots/figures] [--dry-run] [--fresh]

For each spec figures/NAME.toml (--size paper: figures/paper/NAME.toml where it exists) it runs
`xpbd-bench sweep SPEC --out OUT/data/SIZE/NAME.h5` (resumable: a rerun skips finished runs),
then draws the figures into OUT/ and writes OUT/summary.md with every measured number beside the
paper's (numbers from shared/paper/paper_and_code_notes.md). A spec whose scene, solvers or
meshes are missing is run with what exists; a claim whose inputs are missing is reported as
"not run: <reason>", never dropped. Exit status 0 unless the harness itself cannot be run.
"""
import argparse
import datetime
import math
import os
import re
import subprocess
import sys
import time
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import xbruns  # noqa: E402

SPECS = ["squash_xpbd", "squash_mgpbd", "scaling", "near_kernel", "setup_interval", "twist_bar",
         "cloth_stretch", "theta", "stiffness", "error_time", "dual_primal", "dual_primal_bar"]
# --only NAME for a claim whose inputs are several specs (a sweep spec has one scene).
GROUPS = {"dual_primal": ["dual_primal", "dual_primal_bar"]}


# ---------------------------------------------------------------- running the sweeps
def bench_inventory(bench):
    """(scenes, available solvers, unavailable solvers with reasons) from `xpbd-bench list`."""
    out = subprocess.run([bench, "list"], capture_output=True, text=True, check=True).stdout
    scenes, solvers, unavailable, part = set(), set(), {}, None
    for line in out.splitlines():
        if line.strip() in ("scenes:", "solvers:"):
            part = line.strip()[:-1]
            continue
        if not line.startswith("  "):
            continue
        name = line.split()[0]
        if part == "scenes":
            scenes.add(name)
        elif "unavailable:" in line:
            unavailable[name] = line.split("unavailable:", 1)[1].strip()
        else:
            solvers.add(name)
    return scenes, solvers, unavailable


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return repr(v)


def write_spec(spec, path):
    lines = []
    for k, v in spec.items():
        if not isinstance(v, dict):
            lines.append(f"{k} = {toml_value(v)}")
    for table in ("set", "grid"):
        if spec.get(table):
            lines.append(f"[{table}]")
            lines += [f'"{k}" = {toml_value(v)}' for k, v in spec[table].items()]
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("# derived by plots/figures.py (solvers that are not available removed)\n" + "\n".join(lines) + "\n")


def flat_keys(spec):
    out = {}
    for table in ("set", "grid"):
        for k, v in spec.get(table, {}).items():
            out[k] = v if isinstance(v, list) else [v]
    return out


def ensure_meshes(spec, log):
    """Builds the named meshes (bunny:12k) with scripts/get_meshes.sh; returns a reason on failure."""
    names = [m for m in flat_keys(spec).get("mesh", []) if re.fullmatch(r"[a-z]+:\d+k", str(m))]
    script = os.path.join(ROOT, "scripts", "get_meshes.sh")
    if not names or not os.path.exists(script):
        return None
    r = subprocess.run(["bash", script] + names, capture_output=True, text=True)
    log.write(r.stdout + r.stderr)
    if r.returncode != 0:
        tail = (r.stderr.strip().splitlines() or ["?"])[-1]
        return f"scripts/get_meshes.sh {' '.join(names)} failed: {tail}"
    return None


def run_spec(name, args, inventory, notes):
    """Runs one sweep; returns the results path (or None) and records why parts did not run."""
    scenes, solvers, unavailable = inventory
    spec_path = os.path.join(ROOT, "figures", "paper", name + ".toml") if args.size == "paper" else ""
    if not os.path.exists(spec_path):
        spec_path = os.path.join(ROOT, "figures", name + ".toml")
    with open(spec_path, "rb") as f:
        spec = tomllib.load(f)
    data_dir = os.path.join(args.out, "data", args.size)
    out = os.path.join(data_dir, name + ".h5")
    scene = spec.get("scene", "")
    if "/" not in scene and not scene.endswith(".toml") and scene not in scenes:
        notes[name] = f"scene '{scene}' is not registered in this build (xpbd-bench list)"
        return out if os.path.exists(out) else None
    wanted = spec.get("solvers", [])
    missing = [s for s in wanted if s not in solvers]
    if missing:
        why = ", ".join(f"{s} ({unavailable.get(s, 'not registered')})" for s in missing)
        notes[name] = f"solver(s) not available: {why}"
        spec = dict(spec, solvers=[s for s in wanted if s in solvers])
        if not spec["solvers"]:
            return out if os.path.exists(out) else None
        spec_path = os.path.join(data_dir, "specs", name + ".toml")
        write_spec(spec, spec_path)
    os.makedirs(data_dir, exist_ok=True)
    with open(os.path.join(data_dir, name + ".log"), "a") as log:
        reason = None if args.dry_run else ensure_meshes(spec, log)
        if reason:
            notes[name] = (notes.get(name, "") + "; " if name in notes else "") + reason
        cmd = [args.bench, "sweep", spec_path, "--out", out]
        print("$ " + " ".join(cmd), flush=True)
        if args.dry_run:
            return out if os.path.exists(out) else None
        t0 = time.time()
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        log.write(f"$ {' '.join(cmd)}\n{r.stderr}{r.stdout}\n")
        print(r.stdout, end="", flush=True)
        print(f"  ({time.time() - t0:.0f} s)", flush=True)
        if r.returncode != 0:
            tail = (r.stderr.strip().splitlines() or ["?"])[-1]
            notes[name] = (notes.get(name, "") + "; " if name in notes else "") + f"sweep failed: {tail}"
    return out if os.path.exists(out) else None


# ---------------------------------------------------------------- measuring
DATA = ("frame", "substep", "iteration", "dual_residual", "relative_dual_residual", "wall_time", "energy",
        "linear_iterations", "linear_relative_residual", "position_error")


def runs_of(path, **kw):
    return xbruns.load(path, **kw) if path and os.path.exists(path) else []


def by(runs, **match):
    return [r for r in runs if all(str(r["attrs"].get(k)) == str(v) for k, v in match.items())]


def e(v, digits=3):
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


def status_note(run):
    a = run["attrs"]
    s = a.get("status")
    return "" if s in ("ok", "max_iterations") else f"{s}: {a.get('message', '')}"[:160]


class Summary:
    def __init__(self):
        self.rows = []  # (claim, quantity, paper, measured, note)
        self.figures = []
        self.sections = []  # (title, Markdown): a claim's own table after the main one

    def add(self, claim, quantity, paper, measured, note=""):
        self.rows.append((claim, quantity, paper, measured, note))

    def not_run(self, claim, reason):
        self.rows.append((claim, "—", "—", f"not run: {reason}", ""))


def tets(run):
    return e(xbruns.as_number(run["attrs"].get("rows")))


def claim_squash(S, files, notes, out):
    claim = "squash: XPBD stalls, MGPBD reaches 1e-2 in 55–59"
    paper_x = {"bunny:5k": "0.969", "bunny:12k": "0.771", "bunny:270k": "0.727"}
    paper_m = {"bunny:5k": ("118", "7.8 s", "4.0e-4 at 500"), "bunny:12k": ("55", "3.7 s", "3.7e-6 at 500"),
               "bunny:50k": ("68", "8.28 s", "—"), "bunny:270k": ("59", "15.1 s", "1.1e-6 at 459")}
    rx = runs_of(files.get("squash_xpbd"), datasets=DATA)
    rm = runs_of(files.get("squash_mgpbd"), datasets=DATA)
    for key in ("squash_xpbd", "squash_mgpbd"):
        if key in notes:
            S.add(claim, f"inputs of {key}", "—", f"not run: {notes[key]}" if not (rx if key == 'squash_xpbd' else rm)
                  else f"partly run: {notes[key]}")
    for r in rx:
        m = r["attrs"].get("mesh")
        if failed(r):
            S.add(claim, f"{r['attrs'].get('solver')} rel. dual residual after 10⁴ its, {m}", paper_x.get(m, "—"),
                  f"not run: {status_note(r)}")
            continue
        its = int(r["data"]["iteration"][-1])
        S.add(claim, f"{r['attrs'].get('solver')} relative dual residual after {its} its ({tets(r)} tets, {m})",
              paper_x.get(m, "—"),
              f"{e(float(r['data']['relative_dual_residual'][-1]))} ({e(float(r['attrs']['wall_time']))} s)",
              status_note(r))
    for r in rm:
        m = r["attrs"].get("mesh")
        p = paper_m.get(m, ("—", "—", "—"))
        if failed(r):
            S.add(claim, f"MGPBD iterations to 1e-2, {m}", p[0], f"not run: {status_note(r)}")
            continue
        it, t = xbruns.to_tolerance(r, 1e-2)
        S.add(claim, f"mgpbd outer iterations / time to 1e-2 ({tets(r)} tets, {m})", f"{p[0]} / {p[1]}",
              f"{e(it)} / {e(t)} s", status_note(r))
        S.add(claim, f"mgpbd relative dual residual at the end ({m})", p[2],
              f"{e(float(r['data']['relative_dual_residual'][-1]))} at {int(r['data']['iteration'][-1])}")
    if not rx and not rm:
        if "squash_xpbd" not in notes and "squash_mgpbd" not in notes:
            S.not_run(claim, "no results")
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    for r in rx + rm:
        if failed(r):
            continue
        lab = f"{r['attrs'].get('solver')} {r['attrs'].get('mesh')}"
        rel = np.maximum(np.asarray(r["data"]["relative_dual_residual"]), 1e-300)
        it = np.asarray(r["data"]["iteration"])
        axes[0].loglog(np.maximum(it, 1), rel, label=lab)
        axes[1].loglog(np.maximum(np.asarray(r["data"]["wall_time"]), 1e-4), rel, label=lab)
    for ax, xl in zip(axes, ("outer iteration", "wall time (s)")):
        ax.axhline(1e-2, color="k", lw=0.6, ls=":")
        ax.set_xlabel(xl)
        ax.set_ylabel("relative dual residual")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("squash (frame 0): one-sweep XPBD against MGPBD")
    fig.tight_layout()
    xbruns.save(fig, os.path.join(out, "squash_residual.png"))
    S.figures.append("squash_residual.png")


def claim_scaling(S, files, notes, out):
    claim = "time per outer iteration linear in size"
    runs = runs_of(files.get("scaling"), datasets=())
    if not runs:
        S.not_run(claim, notes.get("scaling", "no results"))
        return
    import scaling
    data = scaling.per_iteration(runs, "rows")
    for s, (n, t) in sorted(data.items()):
        if len(n) < 2:
            S.add(claim, f"{s}: R² of the linear fit", "0.998", f"not run: only {len(n)} size(s) finished")
            continue
        k, b, r2 = xbruns.linear_fit(n, t)
        S.add(claim, f"{s}: R² of t = a·tets + b over {len(n)} sizes ({int(n.min())}–{int(n.max())} tets)",
              "0.9978 (mgpbd)" if s == "mgpbd" else "—", f"{r2:.4f}")
        S.add(claim, f"{s}: slope a / intercept b", "0.662 ms per 1K tets / 78.2 ms (RTX 4090)" if s == "mgpbd" else "—",
              f"{k * 1e3:.3g} ms per 1K / {b:.3g} ms (this CPU)")
    if "scaling" in notes:
        S.add(claim, "inputs", "—", f"partly run: {notes['scaling']}")
    plot(S, "scaling.py", files["scaling"], os.path.join(out, "scaling.png"))


def claim_near_kernel(S, files, notes, out):
    claim = "near-kernel: 34 (B = 1) vs 18 (GS) PCG iterations"
    runs = runs_of(files.get("near_kernel"), datasets=DATA)
    if not runs:
        S.not_run(claim, notes.get("near_kernel", "no results"))
        return
    paper = {"ones": "34 (rel. res. 6.4e-7)", "gs": "18 (rel. res. 7.9e-7)"}
    for r in runs:
        nk = r["attrs"].get("amg.near_kernel")
        if failed(r) or "linear_iterations" not in r["data"] or len(r["data"]["linear_iterations"]) < 2:
            S.add(claim, f"PCG iterations, B = {nk}", paper.get(nk, "—"), f"not run: {status_note(r) or 'no solve'}")
            continue
        S.add(claim, f"PCG iterations of the first solve, near_kernel = {nk} ({tets(r)} tets)", paper.get(nk, "—"),
              f"{int(r['data']['linear_iterations'][1])} (rel. res. {e(float(r['data']['linear_relative_residual'][1]))})")


def claim_setup_interval(S, files, notes, out):
    claim = "setup interval 1 → 100: residual after 100 its 1.03e-2 → 1.45e-2"
    runs = runs_of(files.get("setup_interval"), datasets=DATA)
    if not runs:
        S.not_run(claim, notes.get("setup_interval", "no results"))
        return
    paper = {1: "1.025e-2", 10: "1.219e-2", 20: "1.310e-2", 50: "1.404e-2", 100: "1.452e-2"}
    for r in sorted(runs, key=lambda r: int(r["attrs"].get("amg.setup_interval", 0))):
        k = int(r["attrs"].get("amg.setup_interval", 0))
        if failed(r):
            S.add(claim, f"interval {k}", paper.get(k, "—"), f"not run: {status_note(r)}")
            continue
        fr, sub = last_substep(r)
        v = xbruns.value_at_iteration(r, "relative_dual_residual", 100, fr, sub)
        S.add(claim, f"rel. dual residual after 100 its, frame {fr}, setup_interval = {k} ({tets(r)} tets)",
              paper.get(k, "—"), e(v), status_note(r))
    plot(S, "sweep.py", files["setup_interval"], os.path.join(out, "setup_interval.png"),
         ["--metric", "relative_dual_residual"])


def claim_twist(S, files, notes, out):
    claim = "twist bar at 7e9: relative energy 0.03 (MGPBD) vs 0.75 (XPBD)"
    runs = runs_of(files.get("twist_bar"), datasets=DATA)
    if not runs:
        S.not_run(claim, notes.get("twist_bar", "no results"))
        return
    paper = {("mgpbd", 7e7): "0.695", ("mgpbd", 7e8): "0.253", ("mgpbd", 7e9): "0.0315",
             ("xpbd", 7e7): "0.639", ("xpbd", 7e8): "0.694", ("xpbd", 7e9): "0.749"}
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    stiff = sorted({float(r["attrs"].get("stiffness")) for r in runs})
    fig, axes = plt.subplots(1, len(stiff), figsize=(4.4 * len(stiff), 4), squeeze=False)
    for r in sorted(runs, key=lambda r: (float(r["attrs"]["stiffness"]), r["attrs"]["solver"])):
        mu, s = float(r["attrs"]["stiffness"]), r["attrs"]["solver"]
        pk = paper.get(("mgpbd" if s == "mgpbd" else "xpbd" if s.startswith("xpbd") else s, mu), "—")
        if failed(r) or "energy" not in r["data"]:
            S.add(claim, f"{s}, μ = {mu:.0e}", pk, f"not run: {status_note(r)}")
            continue
        m = xbruns.substep_mask(r, 0, 0)
        en = np.asarray(r["data"]["energy"])[m]
        it = np.asarray(r["data"]["iteration"])[m]
        rel = en / en[0] if en[0] > 0 else en
        k = np.flatnonzero(it <= 100)[-1]
        S.add(claim, f"{s}: E(it {int(it[k])}) / E(0), μ = {mu:.0e} ({tets(r)} tets)", pk, e(float(rel[k])),
              status_note(r))
        ax = axes[0][stiff.index(mu)]
        ax.semilogy(it, rel, label=s)
        ax.set_title(f"μ = {mu:.0e} Pa")
        ax.set_xlabel("outer iteration")
        ax.set_ylabel("incremental energy / its value at x̃")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    xbruns.save(fig, os.path.join(out, "twist_bar_energy.png"))
    S.figures.append("twist_bar_energy.png")


def claim_cloth(S, files, notes, out):
    claim = "hanging cloth: XPBD stretches at the same dual residual (Fig. 8)"
    runs = runs_of(files.get("cloth_stretch"), datasets=("final_positions", "distance_edges", "distance_rest_length"))
    if not runs:
        S.not_run(claim, notes.get("cloth_stretch", "no results"))
        return
    for r in runs:
        if failed(r):
            S.add(claim, f"{r['attrs'].get('solver')} max strain", "—", f"not run: {status_note(r)}")
            continue
        s, _, _ = xbruns.cloth_strains(r)
        a = r["attrs"]
        S.add(claim, f"{a.get('solver')}: max / mean edge strain (length/rest − 1) after {a.get('frames')} frames "
                     f"({a.get('resolution')}², stop at dual residual {a.get('atol')})",
              "XPBD visibly stretched, global solve not", f"{s.max():.3g} / {s.mean():.3g}",
              f"{a.get('substeps_converged')}/{a.get('substeps_total')} substeps reached it; {a.get('status')}")
    if "cloth_stretch" in notes:
        S.add(claim, "inputs", "—", f"partly run: {notes['cloth_stretch']}")
    plot(S, "cloth_stretch.py", files["cloth_stretch"], os.path.join(out, "cloth_stretch.png"))


def claim_sweeps(S, files, notes, out):
    claim = "θ_s sweep and stiffness sweep"
    for key, axis in (("theta", "amg.strength_threshold"), ("stiffness", "stiffness")):
        runs = runs_of(files.get(key), datasets=DATA)
        if not runs:
            S.not_run(claim, f"{key}: " + notes.get(key, "no results"))
            continue
        for r in sorted(runs, key=lambda r: (r["attrs"]["solver"], float(r["attrs"].get(axis, 0)))):
            a = r["attrs"]
            if failed(r):
                S.add(claim, f"{a['solver']}, {axis} = {e(float(a.get(axis)))}", "—", f"not run: {status_note(r)}")
                continue
            i2, t2 = xbruns.to_tolerance(r, 1e-2)
            i4, t4 = xbruns.to_tolerance(r, 1e-4)
            S.add(claim, f"{a['solver']}, {axis} = {e(float(a.get(axis)))}: its / time to 1e-2, to 1e-4 ({tets(r)} tets)",
                  "θ_s “small, e.g. 0.25”" if key == "theta" else "—",
                  f"{e(i2)} / {e(t2)} s, {e(i4)} / {e(t4)} s", status_note(r))
        if key in notes:
            S.add(claim, f"{key} inputs", "—", f"partly run: {notes[key]}")
        for metric in ("iterations_to_tolerance", "time_to_tolerance"):
            plot(S, "sweep.py", files[key], os.path.join(out, f"{key}_{metric}.png"), ["--metric", metric, "--tol", "1e-2"])
        if key == "stiffness":
            plot(S, "stability.py", files[key], os.path.join(out, "stiffness_stability.png"))


def claim_error_time(S, files, notes, out):
    claim = "error against run time (Pareto view; no paper number)"
    runs = runs_of(files.get("error_time"), datasets=DATA)
    if not runs:
        S.not_run(claim, notes.get("error_time", "no results"))
        return
    for r in runs:
        a = r["attrs"]
        if failed(r) or "position_error" not in r["data"]:
            S.add(claim, f"{a.get('solver')}", "—", f"not run: {status_note(r)}")
            continue
        pe = np.asarray(r["data"]["position_error"])
        wt = np.asarray(r["data"]["wall_time"])
        hit = np.flatnonzero(pe <= 1e-3)
        S.add(claim, f"{a.get('solver')}: time to position error 1e-3; final error ({tets(r)} tets)", "—",
              f"{e(float(wt[hit[0]])) + ' s' if len(hit) else 'never'}; {e(float(pe[-1]))}",
              f"reference reached {e(float(a.get('reference_dual_residual', math.nan)))} relative")
    if "error_time" in notes:
        S.add(claim, "inputs", "—", f"partly run: {notes['error_time']}")
    plot(S, "error_time.py", files["error_time"], os.path.join(out, "error_time.png"))


def claim_dual_primal(S, files, notes, out):
    import dual_primal  # the claim's code lives in its own module (figures.py stays short)
    dual_primal.claim(S, files, notes, out, GROUPS["dual_primal"])


def plot(S, script, results, out, extra=()):
    r = subprocess.run([sys.executable, os.path.join(HERE, script), results, "-o", out] + list(extra),
                       capture_output=True, text=True)
    if r.returncode == 0:
        S.figures.append(os.path.basename(out))
    else:
        S.add("figures", script, "—", f"not drawn: {(r.stderr.strip().splitlines() or ['?'])[-1]}")


def write_summary(S, args, notes, files, elapsed):
    path = os.path.join(args.out, "summary.md")
    with open(path, "w") as f:
        f.write("# The paper's claims, measured by `make figures`\n\n")
        f.write(f"Size: `{args.size}` (FIGURES_SIZE); generated {datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC "
                f"in {elapsed / 60:.1f} min by `python3 plots/figures.py --size {args.size}`.\n")
        f.write("Paper numbers: shared/paper/paper_and_code_notes.md (authors' data, RTX 4090, float32); "
                "ours: this machine's CPU, double precision. Results files: "
                f"`{os.path.relpath(os.path.join(args.out, 'data', args.size), ROOT)}/*.h5` "
                "(rerunning resumes them).\n\n")
        f.write("| claim | quantity | paper | measured | note |\n|---|---|---|---|---|\n")
        for row in S.rows:
            f.write("| " + " | ".join(str(c).replace("|", "/").replace("\n", " ") for c in row) + " |\n")
        for title, text in S.sections:
            f.write(f"\n## {title}\n\n{text}")
        f.write("\n## Figures\n\n")
        for fig in S.figures:
            f.write(f"- `{fig}` (+ PDF)\n")
        f.write("\n## Definitions\n\n"
                "- relative dual residual: ‖C + α̃λ‖ over its value at the substep's first evaluation.\n"
                "- time to 1e-2: wall time of the first substep (frame 0) until the relative dual residual ≤ 1e-2.\n"
                "- twist-bar relative energy: incremental energy ‖x − x̃‖²_M/(2h²) + Σ C²/(2α) over its value at x̃ "
                "(the paper's normalisation is not stated).\n"
                "- scaling: wall_time / outer_iterations of a run against its rows (= tets for tet scenes).\n")
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--size", default=os.environ.get("FIGURES_SIZE", "default") or "default",
                    choices=["default", "paper"])
    ap.add_argument("--only", default="", help="comma-separated spec names (default: all)")
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "figures"))
    ap.add_argument("--dry-run", action="store_true", help="print the sweeps, summarise existing results")
    ap.add_argument("--fresh", action="store_true",
                    help="delete the selected specs' results first (a rerun otherwise keeps every finished run, "
                         "failed ones included, e.g. from an older build)")
    args = ap.parse_args()
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"figures: {args.bench} is not an executable (build first: make build, or --bench PATH)")
    os.makedirs(args.out, exist_ok=True)
    t0 = time.time()
    inventory = bench_inventory(args.bench)
    only = [s for s in args.only.split(",") if s]
    bad = [s for s in only if s not in SPECS and s not in GROUPS]
    if bad:
        sys.exit(f"figures: unknown spec(s) {', '.join(bad)} (valid: {', '.join(SPECS + list(GROUPS))})")
    only = [x for s in only for x in GROUPS.get(s, [s])]
    notes, files = {}, {}
    for name in SPECS:
        if only and name not in only:
            p = os.path.join(args.out, "data", args.size, name + ".h5")
            files[name] = p if os.path.exists(p) else None
            if not files[name]:
                notes[name] = "not selected (--only)"
            continue
        if args.fresh:
            p = os.path.join(args.out, "data", args.size, name + ".h5")
            if os.path.exists(p):
                os.remove(p)
        files[name] = run_spec(name, args, inventory, notes)
    S = Summary()
    for fn in (claim_squash, claim_scaling, claim_near_kernel, claim_setup_interval, claim_twist, claim_cloth,
               claim_sweeps, claim_error_time, claim_dual_primal):
        try:
            fn(S, files, notes, args.out)
        except Exception as ex:  # a broken claim must not hide the others
            S.add(fn.__name__.replace("claim_", ""), "—", "—", f"not measured: {type(ex).__name__}: {ex}")
    write_summary(S, args, notes, files, time.time() - t0)


if __name__ == "__main__":
    main()
