"""What the tests of the results store share (test_store.py, test_store_kills.py): running the CLI,
reading a file as the plots' loader does, and checking that a file is whole."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import h5py

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import xbruns  # noqa: E402

FAILURES = []
TINY = ["--scene", "cloth_hang", "--set", "resolution=4", "--set", "threads=1", "--frames", "1"]


def fail(case, why):
    FAILURES.append(f"{case}: {why}")
    print(f"FAIL {case}: {why}", flush=True)


def env(extra=None):
    e = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_", "XB_FAULT"))}
    e["OMP_NUM_THREADS"] = "1"
    e.update(extra or {})
    return e


def xb(binary, args, extra=None, cwd=None, timeout=600):
    p = subprocess.run([binary] + args + (["--quiet"] if args[0] in ("run", "sweep", "solve") else []),
                       capture_output=True, text=True, env=env(extra), cwd=cwd, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


def read_names(path):
    """The runs the plots' loader reads (the store, as report reads it) and what it skipped."""
    skipped = []
    try:
        names = [name for name, _ in xbruns.run_groups(path, skipped)]
    except SystemExit as e:
        return [], [str(e)]
    return sorted(names), skipped


def whole(case, path, finished):
    """After the next writer or repair: the index links exactly the store's runs and h5py reads each
    through it; no temporary file, no other store, nothing of the earlier layout; every run of
    `finished` still there. Returns the names."""
    names, skipped = read_names(path)
    if skipped:
        fail(case, f"unreadable runs: {skipped}")
    with h5py.File(path, "r") as f:
        store = f.attrs.get("store", "")  # none: a packed file, its runs inline
        linked = sorted(n for n, g in f["runs"].items() if "status" in g.attrs)
    if linked != names:
        fail(case, f"the index links {len(linked)} runs, the store holds {len(names)}: {sorted(set(linked) ^ set(names))}")
    left = [os.path.join(d, n) for d, _, files in os.walk(path + ".runs") for n in files
            if n.endswith(".tmp") or (d == path + ".runs" and n != "lock")]
    left += [n for n in os.listdir(os.path.dirname(path)) if n.endswith(".tmp")]
    others = [n for n in os.listdir(path + ".runs") if n not in ("lock", store)] if os.path.isdir(path + ".runs") else []
    if left or others:
        fail(case, f"left behind: {left + others}")
    lost = set(finished) - set(names)
    if lost:
        fail(case, f"runs finished before the kill are gone: {sorted(lost)}")
    return names


def spec(folder, name, values, solvers=("xpbd-gs",), sets="", extra=""):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(f'scene = "cloth_hang"\nsolvers = {json.dumps(list(solvers))}\nframes = 1\n{extra}'
                f'[set]\nresolution = 4\nthreads = 1\n{sets}[grid]\ncompliance = {json.dumps(values)}\n')
    return path


def snapshot(path):
    files = {"index": open(path, "rb").read()}
    for d, _, names in os.walk(path + ".runs"):
        files.update({os.path.join(d, n): open(os.path.join(d, n), "rb").read() for n in names if n != "lock"})
    return files


def run_tests(tests, description):
    """The command line of a store test: --binary, --only NAME; exit 1 on any failure."""
    ap = argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--only", help="run only this case (a function name)")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    work = tempfile.mkdtemp(prefix="xb_store_")
    try:
        for test in tests:
            if a.only in (None, test.__name__):
                test(binary, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{os.path.basename(sys.argv[0])}: {len(FAILURES)} failures")
    return 1 if FAILURES else 0
