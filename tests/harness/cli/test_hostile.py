#!/usr/bin/env python3
"""The hostile-input corpus (tests/data/hostile/CASES.tsv) through the CLI: every case must end
with its expected exit code and message fragment, and none with a signal or an internal error.
After every failing case, a results file holding two runs (the target of the cases' --out and
inputs; each case has its own byte-identical copy) must be byte-identical, and no .tmp file may be
left beside it. Cases run in parallel processes (--jobs, default twice the CPU count).

    python3 tests/harness/cli/test_hostile.py --binary build/xpbd-bench [--only ID] [--jobs N]
"""
import argparse
import concurrent.futures
import hashlib
import os
import shlex
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
HOSTILE = os.path.join(ROOT, "tests", "data", "hostile")


def read_cases(path):
    cases = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip() or line.startswith("#"):
                continue
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 4:
                sys.exit("%s:%d: expected 4 tab-separated fields (id, command, exit code, fragment)" % (path, n))
            cases.append((parts[0], parts[1], int(parts[2]), parts[3]))
    return cases


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def expand(command, scratch, good):
    """The command line with its placeholders filled; {COPY:name} copies a corpus file to scratch."""
    out = []
    for word in shlex.split(command):
        while "{COPY:" in word:
            start = word.index("{COPY:")
            end = word.index("}", start)
            name = word[start + 6:end]
            dest = os.path.join(scratch, "copy_" + os.path.basename(name))
            src = os.path.join(HOSTILE, name)
            (shutil.copytree if os.path.isdir(src) else shutil.copy)(src, dest)
            word = word[:start] + dest + word[end + 1:]
        for key, value in (("{D}", HOSTILE), ("{DATA}", os.path.join(ROOT, "tests", "data")), ("{T}", scratch),
                           ("{GOOD}", good), ("{SRC}", ROOT)):
            word = word.replace(key, value)
        out.append(word)
    return out


def run_case(binary, env, case, tmp, pristine, good_digest):
    """One case in its own scratch folder, against its own copy of the two-run results file: a
    failure message, or None."""
    cid, command, code, fragment = case
    scratch = os.path.join(tmp, cid)
    good = os.path.join(tmp, "good", cid, "two_runs.h5")
    os.makedirs(scratch)
    os.makedirs(os.path.dirname(good))
    shutil.copy(pristine, good)
    argv = expand(command, scratch, good)
    try:
        r = subprocess.run([binary] + argv, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return "%s: timed out: %s" % (cid, command)
    said = r.stdout + r.stderr
    problems = []
    if r.returncode < 0:
        problems.append("killed by signal %d" % -r.returncode)
    elif r.returncode != code:
        problems.append("exit %d, expected %d" % (r.returncode, code))
    if "internal error" in said:
        problems.append("an internal error")
    if fragment not in said:
        problems.append("no '%s' in the output" % fragment)
    if code != 0 and digest(good) != good_digest:
        problems.append("changed the two-run results file")
    if os.path.exists(good + ".tmp"):
        problems.append("left " + good + ".tmp")
    if not problems:
        return None
    return "%s: %s\n    $ xpbd-bench %s\n    %s" % (cid, "; ".join(problems), " ".join(argv),
                                                  said.strip().replace("\n", "\n    "))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--only", default="")
    # Twice the CPUs: each case waits most of its time on MPI_Init (a singleton starts its daemon).
    ap.add_argument("--jobs", type=int, default=2 * (os.cpu_count() or 1), help="cases run at once (default: 2 x CPUs)")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    env = dict(os.environ, OMP_WAIT_POLICY="passive", OMP_NUM_THREADS="1")
    cases = [c for c in read_cases(os.path.join(HOSTILE, "CASES.tsv")) if not a.only or c[0] == a.only]
    with tempfile.TemporaryDirectory(prefix="xb_hostile_") as tmp:
        pristine = os.path.join(tmp, "two_runs.h5")
        made = subprocess.run([binary, "run", "--scene", "cloth_hang", "--solver", "xpbd-gs,cholmod", "--set",
                               "resolution=4", "--out", pristine], cwd=ROOT, env=env, capture_output=True, text=True)
        if made.returncode != 0:
            sys.exit("cannot make the two-run results file: " + made.stderr)
        good_digest = digest(pristine)
        # Each case has its own scratch folder and copy of the two-run file, so cases run at once.
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            results = list(pool.map(lambda c: run_case(binary, env, c, tmp, pristine, good_digest), cases))
    failures = [f for f in results if f]
    for f in failures:
        print("FAIL " + f)
    print("hostile corpus: %d cases, %d failed" % (len(cases), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
