#!/usr/bin/env python3
"""Results that do not depend on the thread count (docs/determinism.md), a ctest: a representative
set of runs, each at OMP_NUM_THREADS = 1, 2, 3 and 4 (one process per thread count), compared
record by record, bit for bit: every attribute and every dataset of every run, except the keys
that say when, how fast or on how many threads a run ran (EXCLUDED, each with its reason).

The set: every in-house method (xpbd-jacobi, xpbd-authors, xpbd-gs, cg, jacobi-pcg, mgpbd) on a
tet scene (squash) and on the cloth, the global ones in both forms; mgpbd with the float and the
double V-cycle over two frames (setups and refreshes); a Newton run with --reference; vbd (plain
and Chebyshev) and avbd (on the squash with --reference, the cloth, and the ball in contact with
the ground); a captured system solved in both forms. Sizes are chosen so that every vector spans
several of core/reduce.hpp's chunks of 1,024 indices and every parallel loop runs on all threads (above
kMinParallelRows = 2048).

usage: python3 tests/harness/sim/test_thread_determinism.py --binary build/xpbd-bench [--threads 1,2,3,4]
           [--data FILE.json]
--data: the comparison per case as stamped data (plots/pages.py), which `python3 plots/pages.py
publish FILE.json` makes the results page `determinism` (docs/results/).
"""
import argparse
import io
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import pages  # noqa: E402

# The keys left out of the comparison, each with why it may differ between two runs of the same
# problem and settings; every other attribute and dataset must be the same bits.
EXCLUDED = {
    # clocks: how long something took, or when
    "wall_time": "s, measured (attribute: the run; dataset: per entry)",
    "step_time": "s, measured",
    "fill_time": "s, measured",
    "linear_setup_time": "s, measured",
    "linear_solve_time": "s, measured",
    "linear_history/time": "s since each linear solve began, measured",
    "setup_time_total": "s, measured (mgpbd's statistics)",
    "refresh_time_total": "s, measured (mgpbd's statistics)",
    "reference_time": "s, measured (--reference)",
    "reference/time": "s per substep, measured (--reference)",
    "hessian_time": "s per iteration, measured (the element Hessians under Newton)",
    "setup_time": "s, measured (solve)",
    "solve_time": "s, measured (solve)",
    "time": "s since the solve began, per iteration, measured (solve)",
    "created": "the UTC date and time of the run",
    # the machine's state and the thread count, which is what the test varies
    "load_average": "the 1-minute load at the process's start",
    "peak_memory": "bytes, the process's largest resident set: each thread has its own stack and arena",
    "omp_threads": "OpenMP's thread count: what the test varies",
}


# Each case is one command, run once per thread count ({sys}: the system `capture` writes first).
RUN = ["run", "--set", "max_iterations=2", "--quiet"]
SQUASH = ["--scene", "squash", "--set", "resolution=14"]  # 1,983 particles: dual 8,832 rows, primal 5,949
CAPTURE = ["capture", *SQUASH, "--frame", "0", "--iteration", "1", "--quiet"]
CASES = [
    # a tet scene: every in-house method, the global ones in both forms
    ("squash", [*RUN, *SQUASH, "--frames", "1", "--solver", "xpbd-jacobi,xpbd-gs,xpbd-authors,cg,jacobi-pcg",
                "--form", "dual,primal"]),
    # mgpbd with the float and the double V-cycle; two frames: setups, then refreshes (the dual form
    # refreshes from the second outer iteration on, the primal from the second frame)
    ("squash_mgpbd", [*RUN, *SQUASH, "--frames", "2", "--solver", "mgpbd", "--form", "dual,primal"]),
    ("squash_mgpbd_double", [*RUN, *SQUASH, "--frames", "2", "--solver", "mgpbd", "--form", "dual,primal",
                             "--set", "amg.precision=double"]),
    # the cloth, 64 x 64 particles: primal 12,288 rows
    ("cloth", [*RUN, "--frames", "1", "--scene", "cloth_hang", "--set", "resolution=63",
               "--solver", "xpbd-jacobi,xpbd-gs,xpbd-authors,cg,jacobi-pcg,mgpbd", "--form", "dual,primal"]),
    # the Newton step, with the reference solution of the time step beside it
    ("newton", [*RUN, *SQUASH, "--frames", "1", "--profile", "newton", "--solver", "mgpbd", "--form", "primal",
                "--reference"]),
    # block descent on E (vbd: plain and Chebyshev; avbd: its multipliers and ramp) with the reference
    ("vbd", [*RUN, *SQUASH, "--frames", "2", "--solver", "vbd,avbd", "--reference", "--set", "max_iterations=4"]),
    ("vbd_cloth", [*RUN, "--frames", "1", "--scene", "cloth_hang", "--set", "resolution=63", "--solver", "vbd",
                   "--set", "vbd.acceleration=chebyshev"]),
    # avbd's ground (per-particle multipliers) in contact: ball_drop from frame 9 on
    ("avbd_ground", [*RUN, "--frames", "11", "--scene", "ball_drop", "--set", "resolution=12", "--solver", "avbd"]),
    # the linear level: one captured system solved to 1e-6 (xpbd_bench.solve takes this path too)
    ("solve", ["solve", "--system", "{sys}", "--solver", "cg,jacobi-pcg,mgpbd", "--form", "dual,primal",
               "--tol", "1e-6", "--quiet"]),
]


def excluded(key):
    return key in EXCLUDED


def records(path):
    """{run name: {key: value}} with every attribute and dataset of every run group."""
    out = {}
    with h5py.File(path, "r") as f:
        for name, g in f["runs"].items():
            rec = {f"@{k}": v for k, v in g.attrs.items()}

            def visit(key, obj):
                if isinstance(obj, h5py.Dataset):
                    rec[key] = obj[()]

            g.visititems(visit)
            out[name] = rec
    return out


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind in "fiub":
        return a.tobytes() == b.tobytes()
    return bool(np.all(a == b))


def keys_compared(records_):
    """The attributes and datasets compared, summed over a file's runs."""
    return sum(sum(1 for k in rec if not excluded(k.lstrip("@"))) for rec in records_.values())


def compare(ref, other, label):
    """Every difference between two files' records, one line each."""
    diffs = []
    if sorted(ref) != sorted(other):
        return [f"{label}: runs {sorted(other)} against {sorted(ref)}"]
    for run in ref:
        a, b = ref[run], other[run]
        keys = sorted(k for k in set(a) | set(b) if not excluded(k.lstrip("@")))
        bad = [k for k in keys if k not in a or k not in b or not same_bits(a[k], b[k])]
        if bad:
            diffs.append(f"{label}: {run}: {len(bad)} of {len(keys)} keys differ: {' '.join(bad)}")
    return diffs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--threads", default="1,2,3,4")
    ap.add_argument("--only", default="", help="comma-separated case names")
    ap.add_argument("--data", default="", help="write the comparison as stamped data for plots/pages.py")
    args = ap.parse_args()
    stamp = pages.stamp("python3 tests/harness/sim/test_thread_determinism.py --binary build/xpbd-bench --threads "
                        f"{args.threads} --data {args.data}", microbench=os.path.join(os.path.dirname(args.binary), "xb_microbench")) \
        if args.data else None
    table = pages.Table(["case", "command", "runs", "attributes and datasets compared", "thread counts",
                         "differing runs"], out=io.StringIO())
    threads = [int(t) for t in args.threads.split(",")]
    only = set(filter(None, args.only.split(",")))
    failures, compared = [], 0
    with tempfile.TemporaryDirectory() as tmp:
        system = os.path.join(tmp, "system")
        proc = subprocess.run([args.binary, *CAPTURE, "--out", system], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
        if proc.returncode != 0:
            sys.exit(f"capture: exit {proc.returncode}: {proc.stderr.strip()}")
        for name, command in CASES:
            if only and name not in only:
                continue
            command = [a.replace("{sys}", system + ".h5") for a in command]
            files = {}
            for t in threads:
                out = os.path.join(tmp, f"{name}_{t}.h5")
                env = dict(os.environ, OMP_NUM_THREADS=str(t))
                proc = subprocess.run([args.binary, *command, "--out", out], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, text=True)
                if proc.returncode != 0:
                    failures.append(f"{name} at {t} threads: exit {proc.returncode}: {proc.stderr.strip()}")
                    break
                files[t] = records(out)
            if len(files) < len(threads):
                continue
            base, before = files[threads[0]], len(failures)
            for t in threads[1:]:
                failures += compare(base, files[t], f"{name}, {threads[0]} vs {t} threads")
            compared += len(base)
            table.row([name, "`xpbd-bench " + " ".join(command).replace(system + ".h5", "SYSTEM.h5") + "`", len(base),
                       keys_compared(base), ",".join(map(str, threads)), len(failures) - before])
            print(f"{name}: {len(base)} runs at {threads} threads compared", flush=True)
    if args.data:
        pages.write_data(args.data, "determinism", "The same bits for any thread count", "Every record at each thread count",
                         stamp, [table.data()], "Each case's runs at every thread count, one process each, compared "
                         "attribute by attribute and dataset by dataset, bit for bit, leaving out the clocks, dates, "
                         "the load and the thread count (EXCLUDED in the command's script). " +
                         (f"{len(failures)} difference(s)." if failures else "No record differed."))
    for f in failures:
        print("FAIL:", f)
    if failures:
        sys.exit(1)
    print(f"thread determinism: {compared} runs, bitwise equal at {threads} threads")


if __name__ == "__main__":
    main()
