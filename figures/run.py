#!/usr/bin/env python3
"""`make figures`: run the sweep specs under figures/ and reproduce the paper's claims.

usage: python3 figures/run.py [--bench build/xpbd-bench] [--size default|paper] [--only a,b]
                              [--out plots/figures] [--dry-run] [--fresh] [--quiet] [--data FILE.json]

For each spec figures/NAME.toml it runs `xpbd-bench sweep SPEC --size SIZE --out
OUT/data/SIZE/NAME.h5` (a spec's [sizes.paper] table says what changes at the paper's size;
resumable: a rerun skips finished runs), then plots/claims.py draws the figures into OUT/ and this
driver writes OUT/summary.md with every measured number beside the paper's (numbers from
shared/paper/paper_and_code_notes.md), and the same as stamped data, OUT/claims.json (the machine,
its triad and load taken when this driver starts; the runs' own dates and loads beside them), which
`python3 plots/pages.py publish OUT/claims.json` makes docs/results/claims.md. A spec whose scene, solvers or meshes are missing is run
with what exists; a claim whose inputs are missing is reported as "not run: <reason>", never
dropped. Exit status 0 unless the harness itself cannot be run. On a terminal a status line
(tqdm) follows each sweep: runs done / total, the current run, elapsed and ETA; --quiet: none.
"""
import argparse
import datetime
import os
import re
import subprocess
import sys
import time
import threading
import tomllib

import tqdm

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "plots"))
import claims  # noqa: E402
import pages  # noqa: E402

SPECS = ["squash_xpbd", "squash_mgpbd", "scaling", "near_kernel", "setup_interval", "twist_bar",
         "cloth_stretch", "theta", "stiffness", "error_time", "dual_primal", "dual_primal_bar"]
GROUPS = claims.GROUPS
SIZES = ["default", "paper"]
# Specs run a second time under `sweep --profile authors` (results NAME.authors.h5): the claims whose
# numbers depend on the authors' metric, step rule and AMG settings (plots/profile_claims.py).
PROFILE_SPECS = ["squash_xpbd", "squash_mgpbd", "near_kernel", "setup_interval"]
PROFILE = "authors"


def merged(base, over):
    """`over`'s keys replace or add to `base`'s, tables merged key by key (a [sizes.NAME] table)."""
    out = dict(base)
    for k, v in over.items():
        out[k] = merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def spec_at_size(spec, size):
    """The spec as `xpbd-bench sweep --size SIZE` reads it, without its sizes tables."""
    sizes = spec.get("sizes", {})
    return merged({k: v for k, v in spec.items() if k != "sizes"}, sizes.get(size, {}))


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
        f.write("# derived by figures/run.py (solvers that are not available removed)\n" + "\n".join(lines) + "\n")


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


SWEEP_TOTAL = re.compile(r"^sweep: .*: (\d+) runs \((\d+) already in")
SWEEP_RUN = re.compile(r"^sweep: \[(\d+)/(\d+)\] (.*) \.\.\. (\S+)")


def run_sweep(cmd, label, quiet):
    """Runs `xpbd-bench sweep`, its output kept for the log; on a terminal (and not quiet) a status
    line follows its per-run lines: runs done / total, the last run and its status, and the ETA."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out = []
    reader = threading.Thread(target=lambda: out.append(proc.stdout.read()))  # the summary table
    reader.start()
    err, bar = [], None
    show = sys.stderr.isatty() and not quiet
    for line in proc.stderr:
        err.append(line)
        if not show:
            continue
        if m := SWEEP_TOTAL.match(line):
            bar = tqdm.tqdm(total=int(m.group(1)), initial=int(m.group(2)), desc=label, unit="run", leave=False,
                            dynamic_ncols=True)
        elif (m := SWEEP_RUN.match(line)) and bar is not None:
            bar.update(1)
            bar.set_postfix_str(f"{m.group(3)}: {m.group(4)}", refresh=True)
    proc.wait()
    reader.join()
    if bar is not None:
        bar.close()
    return subprocess.CompletedProcess(cmd, proc.returncode, "".join(out), "".join(err))


def run_spec(name, args, inventory, notes, profile=""):
    """Runs one sweep (under `profile` if given: results NAME.PROFILE.h5, notes under
    NAME@PROFILE); returns the results path (or None) and records why parts did not run."""
    scenes, solvers, unavailable = inventory
    tag = f"{name}@{profile}" if profile else name
    spec_path = os.path.join(HERE, name + ".toml")
    with open(spec_path, "rb") as f:
        spec = spec_at_size(tomllib.load(f), args.size)
    size_args = ["--size", args.size]
    data_dir = os.path.join(args.out, "data", args.size)
    out = os.path.join(data_dir, name + (f".{profile}" if profile else "") + ".h5")
    scene = spec.get("scene", "")
    if "/" not in scene and not scene.endswith(".toml") and scene not in scenes:
        notes[tag] = f"scene '{scene}' is not registered in this build (xpbd-bench list)"
        return out if os.path.exists(out) else None
    wanted = spec.get("solvers", [])
    missing = [s for s in wanted if s not in solvers]
    if missing:
        why = ", ".join(f"{s} ({unavailable.get(s, 'not registered')})" for s in missing)
        notes[tag] = f"solver(s) not available: {why}"
        spec = dict(spec, solvers=[s for s in wanted if s in solvers])
        if not spec["solvers"]:
            return out if os.path.exists(out) else None
        spec_path = os.path.join(data_dir, "specs", name + ".toml")
        write_spec(spec, spec_path)  # already at its size
        size_args = []
    os.makedirs(data_dir, exist_ok=True)
    with open(os.path.join(data_dir, name + ".log"), "a") as log:
        reason = None if args.dry_run else ensure_meshes(spec, log)
        if reason:
            notes[tag] = (notes.get(tag, "") + "; " if tag in notes else "") + reason
        cmd = [args.bench, "sweep", spec_path, "--out", out] + size_args + (["--profile", profile] if profile else [])
        print("$ " + " ".join(cmd), flush=True)
        if args.dry_run:
            return out if os.path.exists(out) else None
        t0 = time.time()
        r = run_sweep(cmd, tag, args.quiet)
        log.write(f"$ {' '.join(cmd)}\n{r.stderr}{r.stdout}\n")
        print(r.stdout, end="", flush=True)
        print(f"  ({time.time() - t0:.0f} s)", flush=True)
        if r.returncode != 0:
            tail = (r.stderr.strip().splitlines() or ["?"])[-1]
            notes[tag] = (notes.get(tag, "") + "; " if tag in notes else "") + f"sweep failed: {tail}"
    return out if os.path.exists(out) else None




def runs_made(files):
    """When the results behind the summary were measured and under what load, from the runs' own
    attributes (a rerun resumes: older runs stay)."""
    import h5py
    made, loads = [], []
    for path in sorted({p for p in files.values() if p}):
        try:
            with h5py.File(path, "r") as f:
                for g in f.get("runs", {}).values():
                    c, lo = g.attrs.get("created"), g.attrs.get("load_average")
                    made += [c.decode() if isinstance(c, bytes) else str(c)] if c is not None else []
                    loads += [float(lo)] if lo is not None else []
        except OSError:
            continue
    if not made:
        return "No runs were found in the results files."
    load = f"; 1-min load at their start {min(loads):.2f}–{max(loads):.2f}" if loads else ""
    return f"The {len(made)} runs behind it were made {min(made)} – {max(made)}{load}."


def write_data(S, args, files, stamp_):
    """The summary as a stamped data file for plots/pages.py (docs/results/claims.md once published)."""
    path = args.data or os.path.join(args.out, "claims.json")
    text = [runs_made(files), "Paper numbers: the authors' data (RTX 4090, float32); ours: this machine's CPU."]
    if S.verdicts:
        text += ["**Verdicts**", "\n".join(f"- **{c}**: {t}" for c, t in S.verdicts)]
    text += [f"**{title}**\n\n{body.strip()}" for title, body in S.sections]
    text += ["**Definitions**: relative dual residual: ‖C + α̃λ‖ over its value at the substep's first evaluation; "
             "time to 1e-2: wall time of the first substep until the relative dual residual ≤ 1e-2; twist-bar "
             "relative energy: ‖x − x̃‖²_M/(2h²) + Σ C²/(2α) over its value at x̃; scaling: wall_time / "
             "outer_iterations against rows (= tets)."]
    tables = [pages.table(["claim", "quantity", "paper", "measured", "note"], S.rows)]
    if S.paired:
        tables.append(pages.table(["claim", "quantity", "paper", "authors' profile", "harness (true metric)"],
                                  S.paired, "Each claim under the authors' profile and under the harness's metric"))
    pages.write_data(path, "claims", "The paper's claims, measured", f"`make figures`, size {args.size}", stamp_,
                     tables, "\n\n".join(text))
    print(f"wrote {path} (publish: python3 plots/pages.py publish {path})")


def write_summary(S, args, notes, files, elapsed):
    path = os.path.join(args.out, "summary.md")
    with open(path, "w") as f:
        f.write("# The paper's claims, measured by `make figures`\n\n")
        f.write(f"Size: `{args.size}` (FIGURES_SIZE); generated {datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC "
                f"in {elapsed / 60:.1f} min by `python3 figures/run.py --size {args.size}`.\n")
        f.write("Paper numbers: shared/paper/paper_and_code_notes.md (authors' data, RTX 4090, float32); "
                "ours: this machine's CPU, double precision. Results files: "
                f"`{os.path.relpath(os.path.join(args.out, 'data', args.size), ROOT)}/*.h5` "
                "(rerunning resumes them).\n\n")
        f.write("| claim | quantity | paper | measured | note |\n|---|---|---|---|---|\n")
        for row in S.rows:
            f.write("| " + " | ".join(str(c).replace("|", "/").replace("\n", " ") for c in row) + " |\n")
        if S.paired or S.verdicts:
            f.write("\n## Each claim twice: under the authors' profile and under the harness's true metric\n\n"
                    "`authors' profile`: the sweep under `--profile authors` (problems/profiles/authors.toml: their "
                    "logged residual stops and is reported, line search, θ_s = 0, Jacobi ω of level 0, smoothed "
                    "coarsest level, bunny 0.2 m tall) — this should match the paper. `harness`: the same sweep "
                    "with the harness's settings, reporting the true dual residual ‖C(x) + α̃λ‖ — what actually "
                    "happens. Time to 1e-2: all / without the setup and the first outer iteration (the paper's "
                    "timing leaves both out).\n\n"
                    "| claim | quantity | paper | authors' profile | harness (true metric) |\n|---|---|---|---|---|\n")
            for row in S.paired:
                f.write("| " + " | ".join(str(c).replace("|", "/").replace("\n", " ") for c in row) + " |\n")
            f.write("\n### Verdicts\n\n")
            for claim, text in S.verdicts:
                f.write(f"- **{claim}**: {text}\n")
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
                    choices=SIZES)
    ap.add_argument("--only", default="", help="comma-separated spec names (default: all)")
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "figures"))
    ap.add_argument("--dry-run", action="store_true", help="print the sweeps, summarise existing results")
    ap.add_argument("--fresh", action="store_true",
                    help="delete the selected specs' results first (a rerun otherwise keeps every finished run, "
                         "failed ones included, e.g. from an older build)")
    ap.add_argument("--quiet", action="store_true", help="no status line on a terminal")
    ap.add_argument("--data", default="", help="the stamped data file for plots/pages.py (default OUT/claims.json)")
    args = ap.parse_args()
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"figures: {args.bench} is not an executable (build first: make build, or --bench PATH)")
    os.makedirs(args.out, exist_ok=True)
    stamp_ = pages.stamp(f"python3 figures/run.py --size {args.size}" + (f" --only {args.only}" if args.only else ""),
                         microbench=os.path.join(os.path.dirname(args.bench), "xb_microbench"))
    t0 = time.time()
    inventory = bench_inventory(args.bench)
    only = [s for s in args.only.split(",") if s]
    bad = [s for s in only if s not in SPECS and s not in GROUPS]
    if bad:
        sys.exit(f"figures: unknown spec(s) {', '.join(bad)} (valid: {', '.join(SPECS + list(GROUPS))})")
    only = [x for s in only for x in GROUPS.get(s, [s])]
    notes, files = {}, {}
    for name in SPECS:
        keys = [(name, name + ".h5")] + ([(f"{name}@{PROFILE}", f"{name}.{PROFILE}.h5")] if name in PROFILE_SPECS else [])
        if only and name not in only:
            for key, fname in keys:
                p = os.path.join(args.out, "data", args.size, fname)
                files[key] = p if os.path.exists(p) else None
                if not files[key]:
                    notes[key] = "not selected (--only)"
            continue
        if args.fresh:
            for _, fname in keys:
                p = os.path.join(args.out, "data", args.size, fname)
                if os.path.exists(p):
                    os.remove(p)
        files[name] = run_spec(name, args, inventory, notes)
        if name in PROFILE_SPECS:
            files[f"{name}@{PROFILE}"] = run_spec(name, args, inventory, notes, PROFILE)
    S = claims.Summary()
    for fn in claims.CLAIMS:
        try:
            fn(S, files, notes, args.out)
        except Exception as ex:  # a broken claim must not hide the others
            S.add(fn.__name__.replace("claim_", ""), "—", "—", f"not measured: {type(ex).__name__}: {ex}")
    write_summary(S, args, notes, files, time.time() - t0)
    write_data(S, args, files, stamp_)


if __name__ == "__main__":
    main()