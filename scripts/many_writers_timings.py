#!/usr/bin/env python3
"""The timings of issue 38 (one results file, many writers), for a quiet machine:

1. an append costs what it adds: one small run appended (by `sweep`) to a ~200 MB results file
   against the same run into a new file: wall time <= 2x + 0.3 s, peak memory <= 1.5x + 100 MB;
2. sweeps in parallel: a 16-run sweep of one-thread jobs with `--jobs 2` and under
   `mpirun -np 2`, each in <= 0.65x the wall time of `--jobs 1`.

    python3 scripts/many_writers_timings.py --binary build/xpbd-bench [--target-mb 200] [--work DIR]

The large file is built once in --work (kept for reruns; about a minute): runs of cloth_hang that
last their time budget log every outer iteration (~4 MB each). The sweep's jobs are of fixed work
(50000 outer iterations of xpbd-gs or cholmod on a small cloth, ~2-6 s each on one core). Only `sweep` is used for the
append, so that an older binary (--binary of main) can be measured the same way. --quick: a 20 MB
file and shorter jobs, to check that the script works (timings under load are not evidence).
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

BASE_SET = "[set]\nresolution = 4\nrtol = 0\natol = 0\nthreads = 1\n"


def clean_env():
    e = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    e["OMP_NUM_THREADS"] = "1"
    return e


CPU = []  # CPU seconds (user + system) of each timed command: what load does not change much


def timed(cmd):
    """(wall s, peak RSS MB) of a command, through /usr/bin/time; raises when it fails."""
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "XB_PEAK_KB %M %U %S"] + cmd, capture_output=True, text=True,
                       env=clean_env())
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr[-1500:]}")
    found = re.findall(r"XB_PEAK_KB (\d+) ([\d.]+) ([\d.]+)", p.stderr)
    CPU.append(sum(float(u) + float(s) for _, u, s in found))
    return wall, max(int(k) for k, _, _ in found) / 1024 if found else float("nan")


def size_of(path):
    """The bytes of a results file: its index and every file of its runs folder."""
    total = os.path.getsize(path) if os.path.exists(path) else 0
    for d, _, files in os.walk(path + ".runs"):  # the runs folder and its store
        total += sum(os.path.getsize(os.path.join(d, f)) for f in files)
    return total


def remove(path):
    if os.path.exists(path):
        os.remove(path)
    shutil.rmtree(path + ".runs", ignore_errors=True)


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def big_file(binary, work, target_mb, budget):
    """A results file of about target_mb, made by one sweep of runs that each last `budget` s."""
    big = os.path.join(work, "big.h5")
    if size_of(big) >= 0.9 * target_mb * 1e6:
        return big
    probe = os.path.join(work, "probe.h5")
    remove(probe)
    spec = lambda repeats: write(os.path.join(work, "big.toml"),  # noqa: E731
                                 f'scene = "cloth_hang"\nsolvers = ["xpbd-gs"]\nframes = 1\ntime_budget = {budget}\n'
                                 f'repeats = {repeats}\n{BASE_SET}[grid]\nmax_iterations = [100000000]\n')
    timed([binary, "sweep", spec(1), "--out", probe, "--quiet"])
    per_run = size_of(probe)
    # Runs vary in size with the machine's speed: grow the sweep (it resumes) until the target.
    repeats = max(2, int(0.7 * target_mb * 1e6 / per_run))
    t0 = time.perf_counter()
    while True:
        print(f"building {big}: {repeats} runs ...", flush=True)
        subprocess.run([binary, "sweep", spec(repeats), "--out", big, "--quiet"], check=True, env=clean_env(),
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        size = size_of(big)
        if size >= 0.95 * target_mb * 1e6:
            break
        repeats += max(1, int((target_mb * 1e6 - size) / (size / repeats) + 0.999))
    print(f"  {size / 1e6:.0f} MB in {time.perf_counter() - t0:.0f} s", flush=True)
    return big


def append_cost(binary, work, big, repeats):
    """Median wall time and peak memory of `sweep` adding one small run to `big` and to a new file."""
    into = {"big": [], "new": []}
    for i in range(repeats):
        small = write(os.path.join(work, "small.toml"),
                      f'scene = "cloth_hang"\nsolvers = ["xpbd-gs"]\nframes = 1\n{BASE_SET}[grid]\n'
                      f'max_iterations = [{20 + (i + int(time.time())) % 1000}]\n')  # a new job each time: 20-1019 iterations
        new = os.path.join(work, "new.h5")
        remove(new)
        into["new"].append(timed([binary, "sweep", small, "--out", new, "--quiet"]) + (CPU[-1],))
        into["big"].append(timed([binary, "sweep", small, "--out", big, "--quiet"]) + (CPU[-1],))
    med = {k: [sorted(x[i] for x in v)[len(v) // 2] for i in range(3)] for k, v in into.items()}
    (tb, mb, cb), (tn, mn, cn) = med["big"], med["new"]
    print(f"append of one run: into a {size_of(big) / 1e6:.0f} MB file {tb:.2f} s ({cb:.2f} s CPU), {mb:.0f} MB; "
          f"into a new file {tn:.2f} s ({cn:.2f} s CPU), {mn:.0f} MB (median of {repeats})")
    ok_t, ok_m = tb <= 2 * tn + 0.3, mb <= 1.5 * mn + 100
    print(f"  time  {'PASS' if ok_t else 'FAIL'}: {tb:.2f} <= 2 x {tn:.2f} + 0.3 = {2 * tn + 0.3:.2f}")
    print(f"  memory {'PASS' if ok_m else 'FAIL'}: {mb:.0f} <= 1.5 x {mn:.0f} + 100 = {1.5 * mn + 100:.0f} MB")
    return ok_t and ok_m


def parallel_sweeps(binary, work, iterations):
    """Wall time of a 16-run sweep of one-thread jobs of fixed work (`iterations` outer iterations
    each, no tolerance met): --jobs 1, --jobs 2, mpirun -np 2."""
    spec = write(os.path.join(work, "jobs.toml"),
                 f'scene = "cloth_hang"\nsolvers = ["xpbd-gs", "cholmod"]\nframes = 1\ntime_budget = 0\n'
                 f'{BASE_SET}max_iterations = {iterations}\n[grid]\ncompliance = [1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2]\n')
    ways = {"--jobs 1": [binary, "sweep", spec, "--jobs", "1"],
            "--jobs 2": [binary, "sweep", spec, "--jobs", "2"],
            "mpirun -np 2": ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2", "-x", "OMP_NUM_THREADS=1",
                             binary, "sweep", spec]}
    wall = {}
    for name, cmd in ways.items():
        out = os.path.join(work, "jobs.h5")
        remove(out)
        wall[name] = timed(cmd + ["--out", out, "--quiet"])[0]
        runs = json.loads(subprocess.run([binary, "report", out, "--format", "json"], capture_output=True, text=True,
                                         env=clean_env()).stdout)
        assert len(runs) == 16, f"{name}: {len(runs)} runs, expected 16"
    one = wall["--jobs 1"]
    print(f"16-run sweep of one-thread jobs ({iterations} iterations each): " +
          ", ".join(f"{k} {v:.1f} s" for k, v in wall.items()))
    ok = True
    for name in ("--jobs 2", "mpirun -np 2"):
        r = wall[name] / one
        ok = ok and r <= 0.65
        print(f"  {name:13s} {'PASS' if r <= 0.65 else 'FAIL'}: {r:.2f} x --jobs 1 (<= 0.65)")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--work", help="folder for the files (default: a temporary one, removed after)")
    ap.add_argument("--target-mb", type=float, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="a 20 MB file and short jobs: checks the script only")
    ap.add_argument("--only", choices=["append", "jobs"])
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    work = a.work or tempfile.mkdtemp(prefix="xb_timings_")
    os.makedirs(work, exist_ok=True)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs; binary {binary}", flush=True)
    ok = True
    try:
        if a.only in (None, "append"):
            big = big_file(binary, work, 20 if a.quick else a.target_mb, 0.3 if a.quick else 1.0)
            ok = append_cost(binary, work, big, a.repeats) and ok
        if a.only in (None, "jobs"):
            ok = parallel_sweeps(binary, work, 5000 if a.quick else 50000) and ok
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
