#!/usr/bin/env python3
"""One results file, many writers (docs/failures.md, results/README.md), through the CLI:

- 8 sweeps appending to one file at once keep all 32 runs, under 32 names;
- 8 `run --out` into one file at once leave it readable and holding one writer's complete runs;
- SIGKILL at random moments of sweep, run and capture: the file opens after each, nothing trips
  the next command, a resume completes every run, and no temporary file outlives the next write;
- a writer waiting for the lock says so;
- sweep --jobs 2, --part K/N and mpirun -np 2 run every job once, with the bits of --jobs 1.

    python3 tests/harness/cli/test_concurrent_writers.py --binary build/xpbd-bench
"""
import argparse
import fcntl
import json
import os
import random
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time

import h5py
import numpy as np

FAILURES = []
RUN = ["--set", "resolution=4", "--set", "threads=1", "--frames", "1"]


def fail(case, why):
    FAILURES.append(f"{case}: {why}")
    print(f"FAIL {case}: {why}", flush=True)


def env():
    """The test's environment without an MPI singleton's variables (mpirun must start clean)."""
    e = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    e["OMP_NUM_THREADS"] = "1"
    return e


def start(binary, args):
    return subprocess.Popen([binary] + args + ["--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env())


def finish(p, timeout=600):
    out, err = p.communicate(timeout=timeout)
    return p.returncode, out + err


def report(binary, path):
    p = subprocess.run([binary, "report", path, "--format", "json"], capture_output=True, text=True, env=env(),
                       timeout=300)
    return p.returncode, p.stdout, p.stderr


def runs_of(path):
    """name -> attrs (strings), read through the index's links with h5py (as the plots do)."""
    out = {}
    with h5py.File(path, "r") as f:
        for name, g in f["runs"].items():
            out[name] = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in g.attrs.items()}
    return out


def positions(path):
    """sweep_key -> final_positions; a key twice is a job run twice."""
    with h5py.File(path, "r") as f:
        runs = [(g.attrs["sweep_key"], np.array(g["final_positions"])) for g in f["runs"].values()]
    out = dict(runs)
    if len(out) != len(runs):
        fail("sweeps over processes", f"{path}: {len(runs)} runs of {len(out)} jobs: a job ran twice")
    return out


def temporaries(folder):
    return [os.path.join(d, f) for d, _, files in os.walk(folder) for f in files if f.endswith(".tmp")]


def spec(folder, name, values, solvers=("xpbd-gs", "cholmod"), extra="", sets=""):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(f'scene = "cloth_hang"\nsolvers = {json.dumps(list(solvers))}\nframes = 1\n{extra}'
                f'[set]\nresolution = 4\nthreads = 1\n{sets}[grid]\ncompliance = {json.dumps(values)}\n')
    return path


def eight_sweeps(binary, work):
    case = "8 concurrent sweeps"
    out = os.path.join(work, "eight", "shared.h5")
    os.makedirs(os.path.dirname(out))
    specs = [spec(work, f"s{i}.toml", [1e-8 * (i + 1), 1e-6 * (i + 1)]) for i in range(8)]
    procs = [start(binary, ["sweep", s, "--out", out]) for s in specs]
    for p in procs:
        rc, text = finish(p)
        if rc != 0:
            fail(case, f"a sweep exited {rc}: {text[-500:]}")
    runs = runs_of(out)
    keys = {r["sweep_key"] for r in runs.values()}
    if len(runs) != 32 or len(keys) != 32:
        fail(case, f"{len(runs)} runs, {len(keys)} sweep keys; expected 32 of each")
    if sorted(n[:4] for n in runs) != [f"{i:04d}" for i in range(1, 33)]:
        fail(case, f"run numbers are not 1..32: {sorted(runs)}")
    if report(binary, out)[0] != 0:
        fail(case, "report does not read the file")
    print(f"{case}: {len(runs)} runs", flush=True)


def eight_run_outs(binary, work):
    case = "8 concurrent run --out"
    out = os.path.join(work, "replace", "r.h5")
    os.makedirs(os.path.dirname(out))
    procs = [start(binary, ["run", "--scene", "cloth_hang", "--solver", "xpbd-gs,cholmod", "--out", out] + RUN +
                   ["--set", f"max_iterations={20 + i}"]) for i in range(8)]
    codes = {}
    for i, p in enumerate(procs):
        rc, text = finish(p)
        codes[20 + i] = rc
        if rc not in (0, 2) or (rc == 2 and "was replaced by another writer" not in text):
            fail(case, f"writer {i} exited {rc}: {text[-500:]}")
    rc, _, err = report(binary, out)
    if rc != 0:
        fail(case, f"report exits {rc}: {err}")
    runs = runs_of(out)
    marks = {r["max_iterations"] for r in runs.values()}
    if len(runs) != 2 or len(marks) != 1:
        fail(case, f"the file holds {len(runs)} runs of writers {marks}; expected one writer's 2 runs")
    elif codes[int(next(iter(marks)))] != 0:
        fail(case, "the writer whose runs the file holds did not succeed")
    print(f"{case}: the file holds writer {marks}'s {len(runs)} runs; exit codes {sorted(codes.values())}", flush=True)


def killed_at_random(binary, work, rng):
    case = "SIGKILL at random moments"
    folder = os.path.join(work, "kill")
    os.makedirs(folder)
    out = os.path.join(folder, "k.h5")
    # Each run lasts its time budget (no tolerance can be met): 24 runs of 0.4 s, so that ten
    # sweeps killed anywhere (a second or two into each) leave work for the resume.
    s = spec(work, "kill.toml", [1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-2], extra="time_budget = 0.4\nrepeats = 2\n",
             sets="max_iterations = 100000000\nrtol = 0\natol = 0\n")
    for i in range(10):
        p = start(binary, ["sweep", s, "--out", out])
        time.sleep(rng.uniform(0.3, 3.0))
        p.send_signal(signal.SIGKILL)
        p.communicate()
        if os.path.exists(out):
            rc, _, err = report(binary, out)
            if rc != 0:
                fail(case, f"after kill {i}: report exits {rc}: {err}")
            print(f"{case}: kill {i}: {len(runs_of(out))} runs kept", flush=True)
    rc, text = finish(start(binary, ["sweep", s, "--out", out]))
    runs = runs_of(out)
    keys = [r["sweep_key"] for r in runs.values()]
    if rc != 0 or len(runs) != 24 or len(set(keys)) != 24:
        fail(case, f"the resume exited {rc} with {len(runs)} runs, {len(set(keys))} keys: {text[-500:]}")
    # run and capture killed the same way: the next one works and leaves no temporary file.
    for args in (["run", "--scene", "cloth_hang", "--solver", "xpbd-gs,cholmod,xpbd-jacobi", "--out", out, "--append"] + RUN,
                 ["capture", "--scene", "cloth_hang", "--set", "resolution=6", "--frame", "0", "--iteration", "0",
                  "--out", os.path.join(folder, "cap")]):
        for i in range(3):
            p = start(binary, args)
            time.sleep(rng.uniform(0.2, 2.0))
            p.send_signal(signal.SIGKILL)
            p.communicate()
        rc, text = finish(start(binary, args))
        if rc != 0:
            fail(case, f"{args[0]} after kills exited {rc}: {text[-500:]}")
    if report(binary, out)[0] != 0:
        fail(case, "the file does not open after the kills of run")
    left = temporaries(folder)
    if left:
        fail(case, f"temporary files outlived the next write: {left}")


def waiting_is_said(binary, work):
    case = "a waiting writer says so"
    out = os.path.join(work, "wait", "w.h5")
    os.makedirs(os.path.dirname(out))
    assert finish(start(binary, ["run", "--scene", "cloth_hang", "--solver", "xpbd-gs", "--out", out] + RUN))[0] == 0
    fd = os.open(out + ".runs/lock", os.O_RDWR)
    fcntl.fcntl(fd, fcntl.F_OFD_SETLKW, struct.pack("hhqqi", fcntl.F_WRLCK, 0, 0, 0, 0))
    p = start(binary, ["run", "--scene", "cloth_hang", "--solver", "xpbd-gs", "--out", out, "--append"] + RUN)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(p.stderr.readline, "")))
    reader.start()
    said = f"waiting for {out}: another writer holds it"
    deadline = time.time() + 300  # the run first, then the wait (slow on a loaded machine)
    while time.time() < deadline and not any(said in ln for ln in lines) and p.poll() is None:
        time.sleep(0.1)
    waited = p.poll() is None
    os.close(fd)  # the lock goes with it
    rc = p.wait(timeout=300)
    reader.join()
    text = "".join(lines)
    if not waited or rc != 0 or said not in text:
        fail(case, f"waited: {waited}, exit {rc}: {text[-500:]}")
    if len(runs_of(out)) != 2:
        fail(case, "the waiting writer's run is not in the file")


def shared_jobs(binary, work):
    """--jobs 2, --part, mpirun -np 2: every job once, each run's bits those of --jobs 1."""
    case = "sweeps over processes"
    s = spec(work, "jobs.toml", [1e-8, 1e-6, 1e-4])
    outs = {}
    for name, cmd in [("one", None), ("jobs2", ["--jobs", "2"]), ("parts", "parts"), ("mpirun", "mpirun")]:
        out = os.path.join(work, "jobs_" + name, "j.h5")
        os.makedirs(os.path.dirname(out))
        if cmd == "parts":
            procs = [start(binary, ["sweep", s, "--out", out, "--part", f"{k}/2"]) for k in range(2)]
            results = [finish(p) for p in procs]
        elif cmd == "mpirun":
            p = subprocess.Popen(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2", "-x", "OMP_NUM_THREADS=1",
                                  binary, "sweep", s, "--out", out, "--quiet"], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, env=env())
            results = [finish(p)]
        else:
            results = [finish(start(binary, ["sweep", s, "--out", out] + (cmd or [])))]
        for rc, text in results:
            if rc != 0:
                fail(case, f"{name}: exit {rc}: {text[-800:]}")
        if name == "mpirun" and "shared by 2 ranks" not in results[0][1]:
            fail(case, f"mpirun: the ranks did not share the jobs: {results[0][1][-500:]}")
        if name == "jobs2" and "on 2 processes" not in results[0][1]:
            fail(case, f"--jobs 2 did not start 2 processes: {results[0][1][-500:]}")
        outs[name] = positions(out)
    for name, got in outs.items():
        if sorted(got) != sorted(outs["one"]):
            fail(case, f"{name}: {len(got)} runs, keys differ from --jobs 1")
        elif any(not np.array_equal(got[k], outs["one"][k]) for k in got):
            fail(case, f"{name}: final positions differ from --jobs 1")
    print(f"{case}: " + ", ".join(f"{n}: {len(v)} runs" for n, v in outs.items()), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--seed", type=int, default=int(time.time()))
    ap.add_argument("--only", help="run only this case (a function name)")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    print(f"test_concurrent_writers: seed {a.seed}", flush=True)
    work = tempfile.mkdtemp(prefix="xb_concurrent_")
    try:
        for test in (eight_sweeps, eight_run_outs, waiting_is_said, shared_jobs):
            if a.only in (None, test.__name__):
                test(binary, work)
        if a.only in (None, "killed_at_random"):
            killed_at_random(binary, work, random.Random(a.seed))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"test_concurrent_writers: {len(FAILURES)} failures")
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
