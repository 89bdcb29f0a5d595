#!/usr/bin/env python3
"""`make race`: the race on the truth of figures/race/race.toml, one process per run.

usage: python3 figures/race.py [--bench build/xpbd-bench] [--spec figures/race/race.toml]
                               [--out plots/race] [--quick | --sizes 0,1] [--only squash,cloth_hang]
                               [--outer xpbd,newton] [--linear mgpbd,cholmod] [--fresh] [--dry-run] [--quiet]

Every entry (an outer method × a linear method × a forcing rule) is `xpbd-bench run --reference`
in a process of its own (a later run in the same process would reuse the earlier one's freed
pages), into OUT/data/<scene>/<size>/<outer>.<linear>.<forcing>.h5; a run whose process wrote none
leaves a .failed.json record (its exit code and last words) instead. A file or record that exists
is a finished entry and is not run again (--fresh starts over). --quick (`make race`): each scene's
`quick_size` with the spec's `quick_forcing`; without it (`make race-full`) every size and every
forcing rule. At each size the anchor (XPBD with exact CHOLMOD, plots/race_rules.py) runs first;
its frame bounds every other entry's time (`budget_factor` times it). A scene with a `state` starts
every entry from the state a `state.solver` run saved after frame `state.frame` (made once per
size under <size>/_state/). Then plots/race.py draws the figures and writes OUT/summary.md. On a
terminal each run shows its live status line (xpbd-bench run's, on the inherited stderr); --quiet
or no terminal: none, and stderr is kept for the failure record. OUT/timings.tsv gets one line per
process: its start (UTC), entry, seconds (the reference's included), exit code and the 1-min load.
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
STOP_KEYS = ("rtol", "atol", "max_iterations")  # an own_stop outer method keeps its profile's


def run_file(out, scene, size, outer, linear, forcing):
    return os.path.join(out, "data", scene, race_plots.safe_name(size), f"{outer}.{linear}.{forcing}.h5")


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
TIMINGS = []  # OUT/timings.tsv


def timing(path, t0, seconds, code, load):
    if TIMINGS:
        os.makedirs(os.path.dirname(TIMINGS[0]), exist_ok=True)
        with open(TIMINGS[0], "a") as fh:
            fh.write(f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime(t0))}\t"
                     f"{os.path.relpath(path, os.path.dirname(TIMINGS[0]))}\t{seconds:.1f}\t{code}\t{load:.2f}\n")


def run_one(bench, path, cmd, dry_run):
    """Runs `cmd` (an `xpbd-bench run` without --out) into `path`, unless it or its failure record
    exists. Returns the run's dict, a failure record's (attrs only, status failed) or None (dry run)."""
    if os.path.exists(failed_file(path)):
        with open(failed_file(path)) as fh:
            return {"attrs": json.load(fh)}
    if not os.path.exists(path):
        cmd = [bench, *cmd, *RUN_FLAGS, "--out", part_of(path)]
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
        timing(path, t0, seconds, done.returncode, load0)
        # A run the binary recorded (whatever its status, error included) is kept; one that left
        # nothing (killed, out of memory, refused) gets a record, and its row in the summary.
        if not os.path.exists(part_of(path)):
            said = (done.stderr or "").strip()[-2000:] if not live else "see the race's stderr"
            print(f"race: exit {done.returncode}; no run recorded for {path}: {said}", file=sys.stderr)
            race_plots.failure_record(failed_file(path), cmd, done.returncode, said, seconds)
            return {"attrs": {"status": "failed", "exit": done.returncode, "message": said}}
        os.replace(part_of(path), path)
        print(f"race: {seconds:.1f} s (exit {done.returncode}, load {os.getloadavg()[0]:.2f})", flush=True)
    runs = xbruns.load(path, datasets=race_plots.datasets())
    return runs[-1] if runs else None


def make_state(args, scene_name, scene, size):
    """The state every entry of this size starts from (scene's `state`), made once; None without."""
    st = scene.get("state")
    if not st:
        return None
    folder = os.path.join(args.out, "data", scene_name, race_plots.safe_name(size["label"]), "_state")
    path = os.path.join(folder, "state.h5")
    if os.path.exists(path):
        return path
    frame = int(st["frame"])
    cmd = [args.bench, "run", "--scene", scene["scene"], "--solver", st.get("solver", "cholmod"), *set_args(size.get("set", {})),
           "--set", f"frames={frame + 1}", "--save-state", path, "--frame-of-state", str(frame), "--quiet",
           "--out", os.path.join(folder, "state_run.h5")]
    print("race:", " ".join(cmd), flush=True)
    if args.dry_run:
        return path
    os.makedirs(folder, exist_ok=True)
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=RUN_ENV, text=True)
    if done.returncode != 0 or not os.path.exists(path):
        sys.exit(f"race: the state of {scene_name} {size['label']} (frame {frame}) was not made: "
                 f"{done.stderr.strip()[-500:]}")
    return path


def entry_sets(spec, scene, size, outer, linear, forcing):
    """The --set keys of one entry: the scene's, the size's, the outer method's, the linear
    method's and the scene's own for that linear method (`linear_set`). XPBD's outer methods run
    `overrun` times the frame's outer iterations; an own_stop one (Newton) keeps its profile's stop
    test; a sweep runs until its time budget."""
    o, m = spec["outer"][outer], spec["linear"][linear]
    sets = sets_of(scene.get("set"), size.get("set"), o.get("set"), m.get("set"), scene.get("linear_set", {}).get(linear))
    if forcing not in ("none",) and m.get("forcing", True) is not False:  # a direct solve has no forcing
        sets["linear.forcing"] = forcing
    if o.get("own_stop"):
        sets = {k: v for k, v in sets.items() if k not in STOP_KEYS}
    elif m.get("local"):
        sets["max_iterations"] = LOCAL_MAX_ITERATIONS
    else:
        sets["max_iterations"] = int(spec.get("overrun", 3) * frame_iterations(scene, size))
    if scene.get("state"):
        sets["frames"] = 1
    return sets


def frame_iterations(scene, size):
    return int(sets_of(scene.get("set"), size.get("set")).get("max_iterations", 100))


def entries(spec, forcing_rules, outers=None, linears=None):
    """(outer, linear, forcing) of every entry, the anchor first (always: it bounds the others)."""
    out = []
    for o in spec["outer"]:
        for name, m in spec["linear"].items():
            if ((outers and o not in outers) or (linears and name not in linears)) and (o, name) != rules.ANCHOR:
                continue
            if m.get("local"):
                if o in m.get("outer", ["xpbd"]):
                    out.append((o, name, "none"))
            else:
                out += [(o, name, f) for f in (["fixed"] if m.get("forcing", True) is False else forcing_rules)]
    return sorted(out, key=lambda e: (e[0], e[1]) != rules.ANCHOR)


def budget(spec, scene, frame):
    """A run's time budget: the spec's, and at most budget_factor (the scene's, else the spec's) ×
    the anchor's frame."""
    if frame is None:
        return spec["time_budget"]
    factor = scene.get("budget_factor", spec.get("budget_factor", 4))
    return min(spec["time_budget"], max(10.0, factor * frame))


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
    """Every entry of one scene, size by size; the anchor first at each."""
    forcing_rules = spec.get("quick_forcing", spec["forcing"]) if args.quick else spec["forcing"]
    todo = entries(spec, forcing_rules, set(filter(None, args.outer.split(","))), set(filter(None, args.linear.split(","))))
    for i in size_indices(args, scene):
        size, frame = scene["sizes"][i], None
        state = make_state(args, scene_name, scene, size)
        for outer, linear, forcing in todo:
            o, m = spec["outer"][outer], spec["linear"][linear]
            sets = entry_sets(spec, scene, size, outer, linear, forcing)
            cmd = ["run", "--scene", scene["scene"], "--solver", m["solver"], "--reference", "--time-budget",
                   f"{spec['time_budget'] if (outer, linear) == rules.ANCHOR else budget(spec, scene, frame):g}",
                   *(["--profile", o["profile"]] if o.get("profile") else []),
                   *(["--load-state", state] if state else []), *set_args(sets)]
            r = run_one(args.bench, run_file(args.out, scene_name, size["label"], outer, linear, forcing), cmd, args.dry_run)
            if (outer, linear) == rules.ANCHOR:
                frame = rules.anchor_frame(r, frame_iterations(scene, size))


def check_spec(bench, spec):
    """Every scene, solver, profile and --set key of the spec is known to the binary (`xpbd-bench list`)."""
    out = subprocess.run([bench, "list"], capture_output=True, text=True, check=True).stdout
    part, names = None, {"scenes": set(), "solvers": set(), "keys": set()}
    for line in out.splitlines():
        if line.endswith(":") and not line.startswith(" "):
            part = {"scenes:": "scenes", "solvers:": "solvers"}.get(line, "keys" if line.startswith("param") else None)
        elif line.startswith("  ") and part:
            names[part].add(line.split()[0])
    bad = [f"{k}: missing" for k in ("outer", "linear", "scenes", "thresholds") if k not in spec]
    if bad:
        sys.exit("race spec: " + "; ".join(bad))
    if rules.ANCHOR[0] not in spec["outer"] or rules.ANCHOR[1] not in spec["linear"]:
        bad.append(f"the anchor (outer {rules.ANCHOR[0]!r}, linear {rules.ANCHOR[1]!r}) must be in the spec")
    for name, o in spec["outer"].items():
        bad += [f"outer.{name}: unknown key {k!r}" for k in o.get("set", {}) if k not in names["keys"]]
        prof = o.get("profile")
        if prof and not os.path.exists(os.path.join(ROOT, "problems", "profiles", f"{prof}.toml")) and not os.path.exists(prof):
            bad.append(f"outer.{name}: unknown profile {prof!r}")
    for name, m in spec["linear"].items():
        if m.get("solver") not in names["solvers"]:
            bad.append(f"linear.{name}: unknown solver {m.get('solver')!r}")
        bad += [f"linear.{name}: unknown key {k!r}" for k in m.get("set", {}) if k not in names["keys"]]
        bad += [f"linear.{name}: unknown outer method {k!r}" for k in m.get("outer", []) if k not in spec["outer"]]
    for name, sc in spec["scenes"].items():
        if sc.get("scene") not in names["scenes"]:
            bad.append(f"scenes.{name}: unknown scene {sc.get('scene')!r}")
        for t in [sc.get("set", {})] + [z.get("set", {}) for z in sc.get("sizes", [])] + list(sc.get("linear_set", {}).values()):
            bad += [f"scenes.{name}: unknown key {k!r}" for k in t if k not in names["keys"]]
        bad += [f"scenes.{name}.linear_set: unknown linear method {k!r}" for k in sc.get("linear_set", {})
                if k not in spec["linear"]]
    if bad:
        sys.exit("race spec: " + "; ".join(bad))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--spec", default=os.path.join(HERE, "race", "race.toml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "race"))
    ap.add_argument("--only", default="", help="comma-separated scene names of the spec")
    ap.add_argument("--sizes", default="", help="comma-separated size indices (0 = smallest)")
    ap.add_argument("--quick", action="store_true", help="each scene's quick_size and quick_forcing only (make race)")
    ap.add_argument("--outer", default="", help="comma-separated outer methods of the spec")
    ap.add_argument("--linear", default="", help="comma-separated linear methods of the spec")
    ap.add_argument("--fresh", action="store_true", help="delete OUT/data first")
    ap.add_argument("--dry-run", action="store_true", help="print the commands only")
    ap.add_argument("--quiet", action="store_true", help="no live status line of each run on a terminal")
    args = ap.parse_args()
    if args.quiet:
        RUN_FLAGS.append("--quiet")
    if not args.dry_run:
        TIMINGS.append(os.path.join(args.out, "timings.tsv"))
    try:
        with open(args.spec, "rb") as fh:
            spec = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as e:
        sys.exit(f"{args.spec}: {e}")
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"{args.bench}: not an executable (build first: make build)")
    check_spec(args.bench, spec)
    for flag, known in (("--only", spec["scenes"]), ("--outer", spec["outer"]), ("--linear", spec["linear"])):
        unknown = set(filter(None, getattr(args, flag[2:]).split(","))) - set(known)
        if unknown:
            sys.exit(f"{flag}: unknown name(s) {', '.join(sorted(unknown))} (spec has {', '.join(known)})")
    scenes = {k: v for k, v in spec["scenes"].items() if not args.only or k in args.only.split(",")}
    if args.fresh and not args.dry_run:
        if os.path.isdir(os.path.join(args.out, "data")):
            shutil.rmtree(os.path.join(args.out, "data"))
        if os.path.exists(TIMINGS[0]):
            os.remove(TIMINGS[0])
    for name, scene in scenes.items():
        run_scene(args, spec, name, scene)
    if not args.dry_run:
        race_plots.draw(os.path.join(args.out, "data"), args.out, spec)


if __name__ == "__main__":
    main()
