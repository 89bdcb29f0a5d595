#!/usr/bin/env python3
"""`make race`, `make race-scale`: the race on the truth of figures/race/race.toml, one process per run.

usage: python3 figures/race.py [--bench build/xpbd-bench] [--spec figures/race/race.toml]
                               [--out plots/race] [--quick | --scale | --sizes 0,1] [--only squash,cloth_hang]
                               [--outer xpbd,newton] [--linear mgpbd,cholmod] [--total-seconds S]
                               [--reference-jobs N] [--fresh] [--dry-run] [--quiet]

Every entry (an outer method × a linear method × a forcing rule) is `xpbd-bench run` in a process
of its own (a later run in the same process would reuse the earlier one's freed pages), into
OUT/data/<scene>/<size>/<outer>.<linear>.<forcing>.h5; a run whose process wrote none leaves a
.failed.json record (its exit code and last words) instead. A file or record that exists is a
finished entry and is not run again (--fresh starts over).

One reference per (scene, size): a size's first process (its reference pass: one sweep of
xpbd-jacobi with `--reference-file`) computes the reference of the judged substep into
OUT/data/<scene>/<size>/_reference/reference.h5, and every entry reads it from there
(`--reference-file`; the binary refuses a file of another problem). --reference-jobs N computes
the references of every planned size first, N processes at a time (entries are always timed one at
a time).

The plan (figures/race_plan.py) predicts each entry's seconds and peak memory from the smaller sizes
already run, gives each its time budget and runs it under a memory limit (`--memory-limit`), skips
what would not fit before it starts, and with a total (--total-seconds; --scale: the spec's
plan.total_seconds) cuts the lowest-priority entries; it is printed before anything runs (and
alone with --dry-run), written to OUT/plan.json and OUT/plan.txt, and made again before each size.

--quick (`make race`): each scene's `quick_size` with the spec's `quick_forcing`; --scale (`make
race-scale`): every size with `quick_forcing`, within plan.total_seconds; neither (`make
race-full`): every size and every forcing rule. At each size the anchor (XPBD with exact CHOLMOD,
plots/race_rules.py) runs first; its frame bounds every other entry's time (`budget_factor` times
it). A scene with a `state` starts every entry from the state a `state.solver` run saved after
frame `state.frame` (made once per size under <size>/_state/). Then plots/race.py draws the figures
and writes OUT/summary.md. On a terminal each run shows its live status line; --quiet or no
terminal: none, and stderr is kept for the failure record. OUT/timings.tsv gets one line per
process: its start (UTC), entry, seconds (the reference's included), exit code, the 1-min load at
its start, the run's status, its peak resident set (bytes) and its dual rows.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "plots"))  # ahead of this folder: `race` is plots/race.py
import race as race_plots  # noqa: E402
import race_plan as plan  # noqa: E402
import race_rules as rules  # noqa: E402
import xbruns  # noqa: E402
from race_spec import (check_spec, entries, entry_sets, frame_iterations,  # noqa: E402,F401
                       reference_sets, set_args, sets_of, size_indices, LOCAL_MAX_ITERATIONS, STOP_KEYS)

# Flags every run gets: --quiet when the race is (no live status line from xpbd-bench run).
RUN_FLAGS = []
# Each method at its best: CHOLMOD's BLAS on every core, as the OpenMP solvers are (the binary's
# own default is one BLAS thread, safe on a loaded machine; at 270k on a quiet one two threads
# factor 1.5x faster: docs/race.md). Runs record it as blas_threads; a value you set is kept.
RUN_ENV = dict(os.environ)
RUN_ENV.setdefault("OPENBLAS_NUM_THREADS", str(os.cpu_count() or 1))
TIMINGS = []  # OUT/timings.tsv


def size_dir(out, scene, size):
    return os.path.join(out, "data", scene, race_plots.safe_name(size))


def run_file(out, scene, size, outer, linear, forcing):
    if outer == plan.REFERENCE:
        return os.path.join(size_dir(out, scene, size), "_reference", "run.h5")
    return os.path.join(size_dir(out, scene, size), f"{outer}.{linear}.{forcing}.h5")


def reference_file(out, scene, size):
    return os.path.join(size_dir(out, scene, size), "_reference", "reference.h5")


def failed_file(path):
    return path[:-3] + ".failed.json"


def part_of(path):
    """Where a run is written until it has finished (a .h5 name, as `run --out` wants)."""
    return path[:-3] + ".part.h5"


def timing(path, t0, seconds, code, load, status="", peak=float("nan"), rows=float("nan")):
    if TIMINGS:
        os.makedirs(os.path.dirname(TIMINGS[0]), exist_ok=True)
        with open(TIMINGS[0], "a") as fh:
            fh.write(f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime(t0))}\t"
                     f"{os.path.relpath(path, os.path.dirname(TIMINGS[0]))}\t{seconds:.1f}\t{code}\t{load:.2f}\t"
                     f"{status}\t{peak:.0f}\t{rows:.0f}\n")


def run_process(cmd, live):
    """Runs cmd; (exit code, its stderr's tail unless live, its peak resident set in bytes)."""
    with tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=None if live else err, env=RUN_ENV, text=True)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        return p.returncode, ("see the race's stderr" if live else err.read()[-2000:].strip()), usage.ru_maxrss * 1024.0


def finish_part(bench, path):
    """A finished run's file takes its final name with its runs folder (results/README.md), and
    `repair` rewrites the index's links for that name (what h5py follows)."""
    if os.path.isdir(path + ".runs"):
        shutil.rmtree(path + ".runs")
    os.replace(part_of(path), path)
    if os.path.isdir(part_of(path) + ".runs"):
        os.replace(part_of(path) + ".runs", path + ".runs")
        subprocess.run([bench, "repair", path], stdout=subprocess.DEVNULL, check=False)


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
        code, said, peak = run_process(cmd, sys.stderr.isatty() and "--quiet" not in RUN_FLAGS)
        seconds = time.time() - t0
        # A run the binary recorded (whatever its status, error included) is kept; one that left
        # nothing (killed, refused) gets a record, and its row in the summary.
        if not os.path.exists(part_of(path)):
            timing(path, t0, seconds, code, load0, "failed", peak)
            print(f"race: exit {code}; no run recorded for {path}: {said}", file=sys.stderr)
            race_plots.failure_record(failed_file(path), cmd, code, said, seconds, load0)
            return {"attrs": {"status": "failed", "exit": code, "message": said}}
        finish_part(bench, path)
        runs = xbruns.load(path, datasets=race_plots.datasets())
        a = runs[-1]["attrs"] if runs else {}
        timing(path, t0, seconds, code, load0, a.get("status", ""), peak, float(a.get("rows", "nan")))
        print(f"race: {seconds:.1f} s, {peak / 1e9:.2f} GB (exit {code}, {a.get('status')}, load "
              f"{os.getloadavg()[0]:.2f})", flush=True)
        return runs[-1] if runs else None
    runs = xbruns.load(path, datasets=race_plots.datasets())
    return runs[-1] if runs else None


def make_state(args, scene_name, scene, size):
    """The state every entry of this size starts from (scene's `state`), made once; None without."""
    st = scene.get("state")
    if not st:
        return None
    folder = os.path.join(size_dir(args.out, scene_name, size["label"]), "_state")
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


def anchor_budget(spec, scene, frame):
    """The bound the anchor's frame sets: budget_factor (the scene's, else the spec's) × it."""
    if frame is None:
        return spec["time_budget"]
    return max(10.0, scene.get("budget_factor", spec.get("budget_factor", 4)) * frame)


def reference_linear(scene, size):
    """The linear method of a size's reference (its `reference.linear`): part of the pass's key."""
    return str(sets_of(scene.get("set"), size.get("set")).get("reference.linear", "cholmod"))


def build_entries(args, spec, scenes, todo):
    """Every process of the race in running order: per scene and size, its reference pass, then
    its entries (the anchor first)."""
    out = []
    for name, scene in scenes.items():
        for i in size_indices(args, scene):
            size = scene["sizes"][i]
            for outer, linear, forcing in [(plan.REFERENCE, reference_linear(scene, size), "none")] + todo:
                path = run_file(args.out, name, size["label"], outer, linear, forcing)
                e = plan.Entry(name, i, size, outer, linear, forcing, os.path.relpath(path, args.out))
                e.done = os.path.exists(path) or os.path.exists(failed_file(path))
                out.append(e)
    return out


def expected_iterations(spec, e):
    """The outer iterations an entry is expected to take, for the prior."""
    sc = spec["scenes"][e.scene]
    if e.outer == plan.REFERENCE or spec["outer"].get(e.outer, {}).get("own_stop"):
        return spec.get("plan", {}).get("newton_iterations", 8)
    return spec.get("overrun", 3) * frame_iterations(sc, e.size)


def replan(args, spec, es, show):
    limit = plan.memory_limit(spec)
    spent, planned = plan.make_plan(spec, es, plan.read_timings(os.path.join(args.out, "timings.tsv")),
                                    lambda e: expected_iterations(spec, e), args.total_seconds, limit)
    text = plan.plan_text(es, spent, planned, args.total_seconds, limit)
    if show:
        print(text, flush=True)
    if not args.dry_run:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "plan.txt"), "w") as fh:
            fh.write(text + "\n")
        with open(os.path.join(args.out, "plan.json"), "w") as fh:
            json.dump(plan.plan_records(es), fh, indent=1)
    return limit


def command(args, spec, e, state, budget_s, limit_gb):
    scene = spec["scenes"][e.scene]
    ref = ["--reference-file", reference_file(args.out, e.scene, e.size["label"])]
    common = ["--time-budget", f"{budget_s:.0f}", "--memory-limit", f"{limit_gb:.1f}", *ref,
              *(["--load-state", state] if state else [])]
    if e.outer == plan.REFERENCE:
        return ["run", "--scene", scene["scene"], "--solver", "xpbd-jacobi", *common, *set_args(reference_sets(scene, e.size))]
    o, m = spec["outer"][e.outer], spec["linear"][e.linear]
    return ["run", "--scene", scene["scene"], "--solver", m["solver"], *common,
            *(["--profile", o["profile"]] if o.get("profile") else []),
            *set_args(entry_sets(spec, scene, e.size, e.outer, e.linear, e.forcing))]


def run_references(args, spec, es):
    """--reference-jobs N: every planned size's reference pass first, up to N processes at a time,
    as many as their predicted peak memory lets share the limit (each capped at its share)."""
    todo = [e for e in es if e.outer == plan.REFERENCE and e.action == "run"]
    limit, running = plan.memory_limit(spec), []
    while todo or running:
        while todo and len(running) < args.reference_jobs:
            e = todo[0]
            free = limit - sum(r[4] for r in running)
            share = free if not running else min(free, max(1.5 * e.bytes / plan.GB, 1.0))
            if running and share < 1.2 * e.bytes / plan.GB:
                break  # it waits for memory
            todo.pop(0)
            sc = spec["scenes"][e.scene]
            cmd = command(args, spec, e, make_state(args, e.scene, sc, e.size), e.budget, share)
            path = os.path.join(args.out, e.rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            print("race (reference):", " ".join([args.bench, *cmd]), flush=True)
            p = subprocess.Popen([args.bench, *cmd, "--quiet", "--out", path], stdout=subprocess.DEVNULL, env=RUN_ENV)
            running.append((p, e, time.time(), os.getloadavg()[0], share))
        p, e, t0, load0, _ = running.pop(0)
        p.wait()
        timing(os.path.join(args.out, e.rel), t0, time.time() - t0, p.returncode, load0, "reference")
        e.done = True


def run_size(args, spec, every, es):
    """One size's processes (`es`): plan `every` entry again with what the smaller sizes measured,
    then run each of this size's."""
    limit = replan(args, spec, every, False)
    scene = spec["scenes"][es[0].scene]
    state, frame = make_state(args, es[0].scene, scene, es[0].size), None
    for e in es:
        if e.done or e.action != "run":
            if not e.done:
                print(f"race: {e.label()}: {e.action}", flush=True)
            continue
        b = e.budget if (e.outer, e.linear) == rules.ANCHOR or e.outer == plan.REFERENCE else \
            min(e.budget, anchor_budget(spec, scene, frame))
        r = run_one(args.bench, os.path.join(args.out, e.rel), command(args, spec, e, state, b, limit), args.dry_run)
        e.done = not args.dry_run
        if (e.outer, e.linear) == rules.ANCHOR:
            frame = rules.anchor_frame(r, frame_iterations(scene, e.size))


def triad_gb_s(bench):
    """The machine's triad bandwidth in GB/s: xb_microbench's triad beside the binary (every core),
    else numpy's (one thread); None where neither runs."""
    micro = os.path.join(os.path.dirname(os.path.abspath(bench)), "xb_microbench")
    if os.access(micro, os.X_OK):
        done = subprocess.run([micro, "--benchmark_filter=^triad", "--benchmark_format=json", "--benchmark_min_time=0.2"],
                              capture_output=True, text=True)
        try:
            rates = [b["bytes_per_second"] for b in json.loads(done.stdout)["benchmarks"] if "bytes_per_second" in b]
            return max(rates) / 1e9 if rates else None
        except (ValueError, KeyError):
            pass
    try:
        import numpy as np
        b, c = np.ones(1 << 24), np.full(1 << 24, 2.0)
        a, best = np.empty_like(b), float("inf")
        for _ in range(5):
            t0 = time.perf_counter()
            np.multiply(c, 3.0, out=a)
            np.add(a, b, out=a)
            best = min(best, time.perf_counter() - t0)
        return 5 * 8 * len(a) / best / 1e9  # two passes: c and a in, a out; a and b in, a out (less a's write-allocate)
    except ImportError:
        return None


def record_machine(args):
    """Appends this part of the race's machine to OUT/machine.json: cores, memory, triad, load."""
    path = os.path.join(args.out, "machine.json")
    parts = plan_read(path)
    with open("/proc/meminfo") as fh:
        total = next((int(line.split()[1]) * 1024 for line in fh if line.startswith("MemTotal:")), 0)
    parts.append(dict(started=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), cpu_count=os.cpu_count(),
                      memory_bytes=total, load_average=os.getloadavg()[0], triad_gb_s=triad_gb_s(args.bench),
                      command=" ".join(sys.argv)))
    os.makedirs(args.out, exist_ok=True)
    with open(path, "w") as fh:
        json.dump(parts, fh, indent=1)


def plan_read(path):
    try:
        with open(path) as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return []


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--spec", default=os.path.join(HERE, "race", "race.toml"))
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "race"))
    ap.add_argument("--only", default="", help="comma-separated scene names of the spec")
    ap.add_argument("--sizes", default="", help="comma-separated size indices (0 = smallest)")
    ap.add_argument("--quick", action="store_true", help="each scene's quick_size and quick_forcing only (make race)")
    ap.add_argument("--scale", action="store_true", help="every size, quick_forcing, within plan.total_seconds")
    ap.add_argument("--outer", default="", help="comma-separated outer methods of the spec")
    ap.add_argument("--linear", default="", help="comma-separated linear methods of the spec")
    ap.add_argument("--total-seconds", type=float, default=None, help="cut what would pass this many s in all")
    ap.add_argument("--reference-jobs", type=int, default=0, help="compute every reference first, N at a time")
    ap.add_argument("--fresh", action="store_true", help="delete OUT/data first")
    ap.add_argument("--dry-run", action="store_true", help="print the plan and the commands only")
    ap.add_argument("--quiet", action="store_true", help="no live status line of each run on a terminal")
    return ap.parse_args()


def main():
    args = parse_args()
    if args.quiet:
        RUN_FLAGS.append("--quiet")
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
    if args.scale and args.total_seconds is None:
        args.total_seconds = spec.get("plan", {}).get("total_seconds")
    scenes = {k: v for k, v in spec["scenes"].items() if not args.only or k in args.only.split(",")}
    if args.fresh and not args.dry_run:
        for old in [os.path.join(args.out, n) for n in ("data", "timings.tsv", "machine.json", "plan.json", "plan.txt")]:
            if os.path.isdir(old):
                shutil.rmtree(old)
            elif os.path.exists(old):
                os.remove(old)
    if not args.dry_run:
        TIMINGS.append(os.path.join(args.out, "timings.tsv"))
    forcing_rules = spec.get("quick_forcing", spec["forcing"]) if args.quick or args.scale else spec["forcing"]
    todo = entries(spec, forcing_rules, set(filter(None, args.outer.split(","))), set(filter(None, args.linear.split(","))))
    es = build_entries(args, spec, scenes, todo)
    replan(args, spec, es, True)
    if not args.dry_run:
        record_machine(args)
    if args.reference_jobs > 0 and not args.dry_run:
        run_references(args, spec, es)
    groups = {}
    for e in es:
        groups.setdefault((e.scene, e.size_index), []).append(e)
    for group in groups.values():
        run_size(args, spec, es, group)
    if not args.dry_run:
        race_plots.draw(os.path.join(args.out, "data"), args.out, spec)


if __name__ == "__main__":
    main()
