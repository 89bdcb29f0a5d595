#!/usr/bin/env python3
"""`make race`: the simulation-level race of figures/race/race.toml, one process per run.

usage: python3 figures/race.py [--bench build/xpbd-bench] [--spec figures/race/race.toml]
                               [--out plots/race] [--quick | --sizes 0,1] [--only squash,cloth_hang]
                               [--methods mgpbd,cholmod] [--fresh] [--dry-run] [--quiet]

Every run is `xpbd-bench run` in a process of its own (a later run in the same process would reuse
the earlier one's freed pages), into OUT/data/<scene>/<size>/<method>.<form>.<forcing>.h5; a run
whose process wrote none leaves a .failed.json record (its exit code and last words) instead. A
file or record that exists is a finished entry and is not run again (--fresh starts over).
--quick (`make race`): each scene's `quick_size` of the spec only; without it (`make race-full`)
every size. The rules (each method's form, the target, what finished) are plots/race_rules.py's:
both forms run at the smallest size with linear.forcing = fixed and the one faster per outer
iteration wins (of those that finished or ran out of time; primal if neither did; a variant takes
its method's form). Exact CHOLMOD runs first at each size; every
other entry then races to the relative dual residual it ended the frame at (rtol = that residual,
at most `overrun` times the frame's outer iterations, at most `budget_factor` times its wall
time). Then plots/race.py draws the figures and writes OUT/summary.md. On a terminal each run
shows its live status line (xpbd-bench run's, on the inherited stderr); --quiet or no terminal:
none, and stderr is kept for the failure record.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race as race_plots  # noqa: E402
import race_rules as rules  # noqa: E402
import xbruns  # noqa: E402

LOCAL_MAX_ITERATIONS = 100000  # a sweep method stops on its time budget, not on a count


def run_file(out, scene, size, method, form, forcing):
    return os.path.join(out, "data", scene, race_plots.safe_name(size), f"{method}.{form}.{forcing}.h5")


def failed_file(path):
    return path[:-3] + ".failed.json"


def part_of(path):
    """Where a run is written until it has finished (a .h5 name, as `run --out` wants)."""
    return path[:-3] + ".part.h5"


def sets_of(*tables):
    out = {}
    for t in tables:
        out.update(t or {})
    return out


def set_args(sets):
    args = []
    for k, v in sets.items():
        args += ["--set", f"{k}={race_plots.toml_text(v)}"]
    return args


# Flags every run gets: --quiet when the race is (no live status line from xpbd-bench run).
RUN_FLAGS = []
# Each method at its best: CHOLMOD's BLAS on every core, as the OpenMP solvers are (the binary's
# own default is one BLAS thread, safe on a loaded machine; at 270k on a quiet one two threads
# factor 1.5x faster: docs/race.md). Runs record it as blas_threads; a value you set is kept.
RUN_ENV = dict(os.environ)
RUN_ENV.setdefault("OPENBLAS_NUM_THREADS", str(os.cpu_count() or 1))


# OUT/timings.tsv: one line per process run (start UTC, entry, s, exit code, 1-min load at start).
TIMINGS = []


def timing(path, t0, seconds, code, load):
    if TIMINGS:
        with open(TIMINGS[0], "a") as fh:
            fh.write(f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime(t0))}\t"
                     f"{os.path.relpath(path, os.path.dirname(TIMINGS[0]))}\t{seconds:.1f}\t{code}\t{load:.2f}\n")


def run_one(bench, path, scene, solver, form, sets, budget, dry_run, reference=False):
    """Runs one race entry into `path` (skipped if it or its failure record exists). Returns the run's
    dict, a failure record's (attrs only, status failed) or None (dry run)."""
    if os.path.exists(failed_file(path)):
        with open(failed_file(path)) as fh:
            return {"attrs": json.load(fh)}
    if not os.path.exists(path):
        cmd = [bench, "run", "--scene", scene, "--solver", solver, "--time-budget", f"{budget:g}",
               *(["--form", form] if form != "none" else []), *(["--reference"] if reference else []),
               *set_args(sets), *RUN_FLAGS, "--out", part_of(path)]
        print("race:", " ".join(cmd), flush=True)
        if dry_run:
            return None
        os.makedirs(os.path.dirname(path), exist_ok=True)
        if os.path.exists(part_of(path)):
            os.remove(part_of(path))
        t0, load0 = time.time(), os.getloadavg()[0]
        live = sys.stderr.isatty() and "--quiet" not in RUN_FLAGS
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=None if live else subprocess.PIPE, env=RUN_ENV,
                              text=True)
        seconds = time.time() - t0
        # A run the binary recorded (whatever its status, error included) is kept; one that left
        # nothing (killed, out of memory, refused) gets a record, and its row in the summary.
        if not os.path.exists(part_of(path)):
            said = (done.stderr or "").strip()[-2000:] if not live else "see the race's stderr"
            print(f"race: exit {done.returncode}; no run recorded for {path}: {said}", file=sys.stderr)
            timing(path, t0, seconds, done.returncode, load0)
            race_plots.failure_record(failed_file(path), cmd, done.returncode, said, seconds)
            return {"attrs": {"status": "failed", "exit": done.returncode, "message": said}}
        os.replace(part_of(path), path)
        print(f"race: {seconds:.1f} s (exit {done.returncode}, load {os.getloadavg()[0]:.2f})", flush=True)
        timing(path, t0, seconds, done.returncode, load0)
    runs = xbruns.load(path, datasets=race_plots.datasets())
    return runs[-1] if runs else None


def budget(spec, exact, scene):
    """A run's time budget: the spec's, and at most budget_factor (the scene's, else the spec's) ×
    exact CHOLMOD's frame."""
    if exact is None:
        return spec["time_budget"]
    factor = scene.get("budget_factor", spec.get("budget_factor", 4))
    return min(spec["time_budget"], max(10.0, factor * exact["time"]))


def entry_sets(spec, scene, size, name, forcing, exact):
    """The --set keys of one entry: the scene's, the size's, the method's and the scene's own for
    that method (`method_set`). Once exact CHOLMOD has run at this size, the others race to its
    end-of-frame residual: rtol = that residual, at most `overrun` times the frame's iterations."""
    m = spec["methods"][name]
    sets = sets_of(scene.get("set"), size.get("set"), m.get("set"), scene.get("method_set", {}).get(name))
    if forcing:
        sets["linear.forcing"] = forcing
    if exact is not None:
        sets.update({"rtol": exact["target"], "atol": 0,
                     "max_iterations": int(spec.get("overrun", 3) * int(sets.get("max_iterations", 100)))})
    if m.get("local"):
        sets["max_iterations"] = LOCAL_MAX_ITERATIONS
    return sets


def exact_of(r):
    """Exact CHOLMOD's frame: its wall time and the relative dual residual it ends at (the rules'
    target); None where it did not finish."""
    if not rules.finished(r):
        return None
    return {"time": float(r["attrs"]["wall_time"]), "target": rules.target(r)}


def choose_form(args, spec, scene_name, scene, size, name, exact, forms):
    """The form of method `name` for this scene (rules.form_of): both forms at the smallest size
    with fixed forcing, or for a variant its method's. Returns the form and that form's run."""
    runs = {}
    m = spec["methods"][name]
    variant = rules.base_of(name, spec["methods"])
    for form in ("dual", "primal") if not variant else (forms.get(variant, rules.FALLBACK_FORM),):
        sets = entry_sets(spec, scene, size, name, "fixed", exact)
        path = run_file(args.out, scene_name, size["label"], name, form, "fixed")
        runs[form] = run_one(args.bench, path, scene["scene"], m["solver"], form, sets, budget(spec, exact, scene), args.dry_run,
                             scene.get("reference", False))
    form = rules.form_of(name, spec["methods"], runs, forms)
    return form, runs.get(form)


def size_indices(args, scene):
    """The sizes to run: --sizes, or with --quick the scene's quick_size (default its first)."""
    sizes = scene["sizes"]
    if args.quick:
        labels = [z["label"] for z in sizes]
        quick = scene.get("quick_size", labels[0])
        if quick not in labels:
            sys.exit(f"race spec: quick_size {quick!r} is not one of the scene's sizes ({', '.join(labels)})")
        return [labels.index(quick)]
    chosen = [int(i) for i in args.sizes.split(",")] if args.sizes else list(range(len(sizes)))
    bad = [i for i in chosen if not 0 <= i < len(sizes)]
    if bad:
        sys.exit(f"--sizes: no size {bad[0]} (the scene has {len(sizes)})")
    return chosen


def run_scene(args, spec, scene_name, scene):
    """Every entry of one scene; exact CHOLMOD first at each size (the others race to its residual)."""
    sizes = scene["sizes"]
    methods = {k: v for k, v in spec["methods"].items() if not args.methods or k in args.methods.split(",")}
    order = sorted(methods, key=lambda k: k != "cholmod")
    forms, exact = {}, None
    for name in order:
        if not methods[name].get("local"):
            forms[name], r = choose_form(args, spec, scene_name, scene, sizes[0], name, exact, forms)
            if name == "cholmod":
                exact = exact_of(r)
    print(f"race: {scene_name} forms: " + ", ".join(f"{k} {v}" for k, v in forms.items()), flush=True)
    for i in size_indices(args, scene):
        size, exact = sizes[i], None
        for name in order:
            m = methods[name]
            form = "none" if m.get("local") else forms[name]
            rules_ = ["none"] if m.get("local") else spec["forcing"] if m.get("forcing", True) else ["fixed"]
            for forcing in rules_:
                sets = entry_sets(spec, scene, size, name, None if forcing == "none" else forcing, exact)
                path = run_file(args.out, scene_name, size["label"], name, form, forcing)
                r = run_one(args.bench, path, scene["scene"], m["solver"], form, sets, budget(spec, exact, scene), args.dry_run,
                            scene.get("reference", False))
                if name == "cholmod":
                    exact = exact_of(r)
    return forms


def check_spec(bench, spec):
    """Every scene, solver and --set key of the spec is known to the binary (`xpbd-bench list`)."""
    out = subprocess.run([bench, "list"], capture_output=True, text=True, check=True).stdout
    part, names = None, {"scenes": set(), "solvers": set(), "keys": set()}
    for line in out.splitlines():
        if line.endswith(":") and not line.startswith(" "):
            part = {"scenes:": "scenes", "solvers:": "solvers"}.get(line, "keys" if line.startswith("param") else None)
        elif line.startswith("  ") and part:
            names[part].add(line.split()[0])
    bad = []
    for name, m in spec["methods"].items():
        if m.get("solver") not in names["solvers"]:
            bad.append(f"methods.{name}: unknown solver {m.get('solver')!r}")
        bad += [f"methods.{name}: unknown key {k!r}" for k in m.get("set", {}) if k not in names["keys"]]
    for name, m in spec["methods"].items():
        base = m.get("variant_of")
        if base is not None and (base not in spec["methods"] or list(spec["methods"]).index(base) > list(spec["methods"]).index(name)):
            bad.append(f"methods.{name}: variant_of {base!r} is not a method listed before it")
    for name, sc in spec["scenes"].items():
        if sc.get("scene") not in names["scenes"]:
            bad.append(f"scenes.{name}: unknown scene {sc.get('scene')!r}")
        for t in [sc.get("set", {})] + [z.get("set", {}) for z in sc.get("sizes", [])] + \
                list(sc.get("method_set", {}).values()):
            bad += [f"scenes.{name}: unknown key {k!r}" for k in t if k not in names["keys"]]
        bad += [f"scenes.{name}.method_set: unknown method {k!r}" for k in sc.get("method_set", {})
                if k not in spec["methods"]]
    if bad:
        sys.exit("race spec: " + "; ".join(bad))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--spec", default=os.path.join(HERE, "race", "race.toml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "race"))
    ap.add_argument("--only", default="", help="comma-separated scene names of the spec")
    ap.add_argument("--sizes", default="", help="comma-separated size indices (0 = smallest)")
    ap.add_argument("--quick", action="store_true", help="each scene's quick_size only (make race)")
    ap.add_argument("--methods", default="", help="comma-separated method labels of the spec")
    ap.add_argument("--fresh", action="store_true", help="delete OUT/data first")
    ap.add_argument("--dry-run", action="store_true", help="print the commands only")
    ap.add_argument("--quiet", action="store_true", help="no live status line of each run on a terminal")
    args = ap.parse_args()
    if args.quiet:
        RUN_FLAGS.append("--quiet")
    TIMINGS.append(os.path.join(args.out, "timings.tsv"))
    try:
        with open(args.spec, "rb") as fh:
            spec = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as e:
        sys.exit(f"{args.spec}: {e}")
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"{args.bench}: not an executable (build first: make build)")
    check_spec(args.bench, spec)
    scenes = {k: v for k, v in spec["scenes"].items() if not args.only or k in args.only.split(",")}
    unknown = set(filter(None, args.only.split(","))) - set(spec["scenes"])
    if unknown:
        sys.exit(f"--only: unknown scene(s) {', '.join(sorted(unknown))} (spec has {', '.join(spec['scenes'])})")
    if args.fresh and os.path.isdir(os.path.join(args.out, "data")):
        shutil.rmtree(os.path.join(args.out, "data"))
    for name, scene in scenes.items():
        run_scene(args, spec, name, scene)
    if not args.dry_run:
        race_plots.draw(os.path.join(args.out, "data"), args.out, spec)


if __name__ == "__main__":
    main()
