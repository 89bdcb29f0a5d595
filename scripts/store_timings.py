#!/usr/bin/env python3
"""The timings of the results store (results/README.md), for a quiet machine, through the CLI:

1. neighbour: `run --out NEW.h5` of one tiny run into a folder that also holds a 10,000-run results
   file, against the same into an empty folder: |difference| <= 0.1 s, and that file untouched;
2. sweep: a 5,000-run sweep of tiny runs (repeats of one job): its overhead (wall time less the
   runs' own `wall_time`) <= 2x what a 10-run sweep's overhead per run predicts (500x it);
3. append: one `run --append` of a tiny run to a 10,000-run file <= 2x (+ 0.1 s) one to a 10-run file.

    python3 scripts/store_timings.py --binary build/xpbd-bench [--work DIR] [--repeat 5] [--only NAME] [--quick]

The large files are built by scripts/build_results_store.py (seconds); what is timed is the real
CLI. Medians of --repeat; the 1-min load average is printed beside them (timings under load are
not evidence). --quick: 1,000-run files and a 500-run sweep, to check that the script works.
"""
import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import build_results_store  # noqa: E402

TINY = ["--scene", "cloth_hang", "--set", "resolution=4", "--set", "threads=1", "--set", "max_iterations=5",
        "--frames", "1", "--solver", "xpbd-gs", "--quiet"]


def env():
    e = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_", "XB_FAULT"))}
    e["OMP_NUM_THREADS"] = "1"
    return e


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


CPU = {}  # command kind -> CPU seconds (user + system) of its runs: what load changes least


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd, kind=None):
    t, c = time.perf_counter(), cpu_children()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env())
    took = time.perf_counter() - t
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr[-1500:]}")
    if kind:
        CPU.setdefault(kind, []).append(cpu_children() - c)
    return took


def snapshot(path):
    files = [path] + [os.path.join(d, n) for d, _, ns in os.walk(path + ".runs") for n in ns]
    return {p: (os.stat(p).st_mtime_ns, os.stat(p).st_size) for p in files}


def neighbour(binary, work, big, repeat):
    empty = os.path.join(work, "empty")
    os.makedirs(empty, exist_ok=True)
    before = snapshot(big)
    into_empty, beside = [], []
    for i in range(repeat):
        into_empty.append(timed([binary, "run"] + TINY + ["--out", os.path.join(empty, f"n{i}.h5")], "into_empty"))
        beside.append(timed([binary, "run"] + TINY + ["--out", os.path.join(os.path.dirname(big), f"n{i}.h5")], "beside_big"))
    a, b = statistics.median(into_empty), statistics.median(beside)
    untouched = snapshot(big) == before
    return dict(into_empty_s=a, beside_big_s=b, difference_s=b - a, untouched=untouched,
                met=abs(b - a) <= 0.1 and untouched)


def sweep_overhead(binary, work, runs):
    spec = os.path.join(work, f"sweep{runs}.toml")
    with open(spec, "w") as f:
        f.write(f'scene = "cloth_hang"\nsolvers = ["xpbd-gs"]\nframes = 1\nrepeats = {runs}\n'
                '[set]\nresolution = 4\nthreads = 1\nmax_iterations = 5\n')
    out = os.path.join(work, f"sweep{runs}.h5")
    for p in (out, out + ".runs"):
        shutil.rmtree(p) if os.path.isdir(p) else os.path.exists(p) and os.remove(p)
    wall = timed([binary, "sweep", spec, "--out", out, "--quiet"], f"sweep_{runs}")
    with h5py.File(out, "r") as f:
        own = sum(float(g.attrs["wall_time"]) for g in f["runs"].values())
        n = len(f["runs"])
    if n != runs:
        raise RuntimeError(f"the {runs}-run sweep left {n} runs")
    return wall, own


def sweep(binary, work, big_runs):
    small_wall, small_own = sweep_overhead(binary, work, 10)
    wall, own = sweep_overhead(binary, work, big_runs)
    per_run = (small_wall - small_own) / 10
    overhead = wall - own
    return dict(ten_wall_s=small_wall, ten_own_s=small_own, ten_overhead_per_run_s=per_run, runs=big_runs,
                big_wall_s=wall, big_own_s=own, big_overhead_s=overhead, predicted_s=big_runs * per_run,
                ratio=overhead / (big_runs * per_run), met=overhead <= 2 * big_runs * per_run)


def append(binary, work, big, repeat):
    small = build_results_store.build(binary, 10, os.path.join(work, "ten", "r.h5"))
    into_small, into_big = [], []
    for _ in range(repeat):
        into_small.append(timed([binary, "run"] + TINY + ["--out", small, "--append"], "append_10"))
        into_big.append(timed([binary, "run"] + TINY + ["--out", big, "--append"], "append_big"))
    a, b = statistics.median(into_small), statistics.median(into_big)
    return dict(into_10_s=a, into_big_s=b, limit_s=2 * a + 0.1, met=b <= 2 * a + 0.1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--work", help="folder for the files (kept); default: a temporary one, removed")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--only", choices=["neighbour", "sweep", "append"])
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    work = a.work or tempfile.mkdtemp(prefix="xb_store_timings_")
    os.makedirs(work, exist_ok=True)
    big_runs, sweep_runs = (1000, 500) if a.quick else (10000, 5000)
    results = {"load_at_start": load()}
    try:
        big = os.path.join(work, "big", "r.h5")
        if a.only in (None, "neighbour", "append"):
            os.makedirs(os.path.dirname(big), exist_ok=True)
            t = time.perf_counter()
            build_results_store.build(binary, big_runs, big)
            results["built"] = dict(runs=big_runs, seconds=time.perf_counter() - t)
        if a.only in (None, "neighbour"):
            results["neighbour"] = neighbour(binary, work, big, a.repeat)
        if a.only in (None, "append"):
            results["append"] = append(binary, work, big, a.repeat)
        if a.only in (None, "sweep"):
            results["sweep"] = sweep(binary, work, sweep_runs)
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)
    results["load_at_end"] = load()
    results["cpu_s_median"] = {k: statistics.median(v) for k, v in CPU.items()}
    print(json.dumps(results, indent=1))
    missed = [k for k, v in results.items() if isinstance(v, dict) and v.get("met") is False]
    print("store_timings: " + ("every limit met" if not missed else "missed: " + ", ".join(missed)))
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
