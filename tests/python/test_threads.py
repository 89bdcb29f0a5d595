"""Python threads and processes sharing the package and one results file: two threads in
xb.solve at once both write their results (libhdf5, not thread-safe here, is entered under one
lock; it used to crash the interpreter in H5Dget_type), threads appending to one file keep every
run, and a killed xb.run leaves the file readable and nothing behind. Each case is its own
interpreter, so that a crash is a failed test, not a dead pytest."""
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

import pytest

THREADS = """
import json, sys, threading
import xpbd_bench as xb
system, outs, append = sys.argv[1], sys.argv[2:], {append}
errors = []
def solve(out, solver):
    try:
        for _ in range({repeat}):
            xb.solve(system, solvers=[solver], out=out, append=append)
    except Exception as e:  # noqa: BLE001 - reported below
        errors.append(repr(e))
threads = [threading.Thread(target=solve, args=(out, s)) for out, s in zip(outs, ["cg", "cholmod"])]
for t in threads: t.start()
for t in threads: t.join()
print(json.dumps({{"errors": errors, "runs": [[r["name"] for r in xb.read(o)] for o in sorted(set(outs))]}}))
"""


def interpreter(script, args, timeout=600):
    e = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run([sys.executable, "-c", script] + args, capture_output=True, text=True, env=e, timeout=timeout)


@pytest.fixture(scope="module")
def system(bench):
    d = tempfile.mkdtemp(prefix="xb_py_threads_")
    prefix = os.path.join(d, "sys")
    assert subprocess.run([bench, "capture", "--scene", "cloth_hang", "--set", "resolution=12", "--frame", "0",
                           "--iteration", "0", "--out", prefix, "--quiet"], capture_output=True).returncode == 0
    return prefix + ".h5"


def test_two_threads_in_solve_at_once_both_write(system):
    d = os.path.dirname(system)
    outs = [os.path.join(d, "a.h5"), os.path.join(d, "b.h5")]
    p = interpreter(THREADS.format(append=False, repeat=4), [system] + outs)
    assert p.returncode == 0, f"the interpreter died ({p.returncode}): {p.stderr[-2000:]}"
    result = json.loads(p.stdout.splitlines()[-1])
    assert result["errors"] == [], result
    assert result["runs"] == [["0001_sys_cg"], ["0001_sys_cholmod"]], result


def test_threads_appending_to_one_file_keep_every_run(system):
    out = os.path.join(os.path.dirname(system), "shared.h5")
    p = interpreter(THREADS.format(append=True, repeat=3), [system, out, out])
    assert p.returncode == 0, f"the interpreter died ({p.returncode}): {p.stderr[-2000:]}"
    result = json.loads(p.stdout.splitlines()[-1])
    assert result["errors"] == [], result
    names = result["runs"][0]
    assert len(names) == 6 and sorted(n[:4] for n in names) == [f"{i:04d}" for i in range(1, 7)], names
    assert sorted(n[5:] for n in names) == ["sys_cg"] * 3 + ["sys_cholmod"] * 3, names


def test_a_killed_run_leaves_a_readable_file_and_nothing_behind():
    d = tempfile.mkdtemp(prefix="xb_py_kill_")
    out = os.path.join(d, "r.h5")
    script = ("import sys, xpbd_bench as xb\n"
              "xb.run('cloth_hang', solvers=['xpbd-gs', 'cholmod'] * 20, out=sys.argv[1], frames=1, set={'resolution': 6})\n")
    kept = 0
    for delay in (1.0, 2.5, 4.0):
        e = dict(os.environ, OMP_NUM_THREADS="1")
        p = subprocess.Popen([sys.executable, "-c", script, out], env=e, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        p.send_signal(signal.SIGKILL)
        p.wait()
        if os.path.exists(out):
            check = interpreter("import sys, xpbd_bench as xb; print(len(xb.read(sys.argv[1])))", [out])
            assert check.returncode == 0, check.stderr
            assert int(check.stdout) >= kept
            kept = int(check.stdout)
    # No temporary folder (xb.run used to stage its runs in xpbd_bench_run_* beside the file).
    assert not [f for f in os.listdir(d) if f.startswith("xpbd_bench_run")], os.listdir(d)
