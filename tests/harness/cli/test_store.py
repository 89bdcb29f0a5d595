#!/usr/bin/env python3
"""The results store through the CLI, the plots' loader and the Python package (results/README.md,
docs/failures.md); the kills at every durable step are test_store_kills.py's:

- a file system whose locks fail (XB_FAULT_LOCK=1:ENOLCK): 8 run --append at once all refuse with
  one line naming the file system, the file as it was;
- two identical sweeps at once: one run per job;
- a run file gone or damaged: report and two plots say one line naming it, no traceback;
- a writer stopped inside its commit (XB_FAULT_SIGNAL=N:SIGSTOP): report, the plots' loader and
  xpbd_bench.read return within a second;
- renamed with its folder, copied elsewhere, a symlinked --out: every run read by report, the
  plots' loader and xpbd_bench.read from another working directory, and by h5py after repair;
- a run into a folder that holds a 1,000-run file (scripts/build_results_store.py) leaves it untouched.

    python3 tests/harness/cli/test_store.py --binary build/xpbd-bench [--only NAME]
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import h5py

from store_support import ROOT, TINY, env, fail, read_names, run_tests, snapshot, spec, xb
import build_results_store  # noqa: E402 (scripts/, on the path store_support sets)


def locks_fail(binary, work):
    case = "locks that fail"
    out = os.path.join(work, "nolock", "r.h5")
    os.makedirs(os.path.dirname(out))
    assert xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs", "--out", out])[0] == 0
    before = snapshot(out)
    procs = [subprocess.Popen([binary, "run"] + TINY + ["--solver", "xpbd-gs", "--out", out, "--append", "--quiet"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=env({"XB_FAULT_LOCK": "1:ENOLCK"})) for _ in range(8)]
    for p in procs:
        _, err = p.communicate(timeout=600)
        lines = [ln for ln in err.splitlines() if ln.startswith("xpbd-bench:")]
        if p.returncode != 2 or len(lines) != 1 or "does not lock files" not in lines[0] or " at /" not in lines[0]:
            fail(case, f"exit {p.returncode}, expected 2 and one line naming the file system: {err[-500:]}")
    if snapshot(out) != before:
        fail(case, "the file changed")
    print(f"{case}: 8 writers refused; e.g. {lines[0] if lines else '-'}", flush=True)


def identical_sweeps(binary, work):
    case = "two identical sweeps at once"
    out = os.path.join(work, "twin", "r.h5")
    os.makedirs(os.path.dirname(out))
    # Runs of 0.3 s (their time budget: no tolerance can be met), so that the sweeps overlap.
    s = spec(work, "twin.toml", [1e-8, 1e-6, 1e-4], solvers=("xpbd-gs", "cholmod"),
             sets="max_iterations = 100000000\nrtol = 0\natol = 0\n", extra="time_budget = 0.3\n")
    procs = [subprocess.Popen([binary, "sweep", s, "--out", out, "--quiet"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env()) for _ in range(2)]
    said = 0
    for p in procs:
        _, err = p.communicate(timeout=600)
        said += err.count("holds this job already")
        if p.returncode != 0:
            fail(case, f"a sweep exited {p.returncode}: {err[-500:]}")
    with h5py.File(out, "r") as f:
        keys = [g.attrs["sweep_key"] for g in f["runs"].values()]
    if len(keys) != 6 or len(set(keys)) != 6:
        fail(case, f"{len(keys)} runs of {len(set(keys))} jobs; expected 6 of 6")
    print(f"{case}: {len(keys)} runs, {len(set(keys))} jobs ({said} runs not kept, their job held already)", flush=True)


def one_line_each(case, err, needles, command):
    """stderr of a reader: one line per needle, each naming it, and no traceback."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "Traceback" in err:
        fail(case, f"{command}: a traceback: {err[-1500:]}")
    for needle in needles:
        if len([ln for ln in lines if needle in ln]) != 1:
            fail(case, f"{command}: not one line naming {needle}: {lines}")


def damaged_runs(binary, work):
    case = "a run file gone or damaged"
    out = os.path.join(work, "dangling", "r.h5")
    os.makedirs(os.path.dirname(out))
    assert xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs,cholmod,xpbd-jacobi,cg", "--out", out])[0] == 0
    with h5py.File(out, "r") as f:
        folder = os.path.join(out + ".runs", f.attrs["store"])
    os.remove(os.path.join(folder, "0002_cloth_hang_cholmod.h5"))
    with open(os.path.join(folder, "0003_cloth_hang_xpbd-jacobi.h5"), "r+b") as fh:
        fh.truncate(100)
    needles = ["0002_cloth_hang_cholmod", "0003_cloth_hang_xpbd-jacobi"]
    rc, text, err = xb(binary, ["report", out])
    one_line_each(case, err, needles, "report")
    if rc != 1 or "xpbd-gs" not in text or " cg " not in text:
        fail(case, f"report exits {rc} (expected 1) or leaves out a readable run: {text}")
    for plot in ("error_time.py", "stability.py"):
        p = subprocess.run([sys.executable, os.path.join(ROOT, "plots", plot), out, "-o",
                            os.path.join(work, "dangling", plot + ".png")], capture_output=True, text=True, env=env())
        one_line_each(case, p.stderr, needles, plot)
        if p.returncode != 0:
            fail(case, f"{plot} exits {p.returncode}: {p.stderr[-800:]}")
    print(f"{case}: report and the plots name each in one line", flush=True)


def wait_stopped(p, timeout=300):
    deadline = time.time() + timeout
    while time.time() < deadline and p.poll() is None:
        with open(f"/proc/{p.pid}/stat") as fh:
            if fh.read().split(")")[-1].split()[0] == "T":
                return True
        time.sleep(0.05)
    return False


def python_read(path, cwd=None):
    """xpbd_bench.read in its own interpreter (PYTHONPATH from ctest): (exit, names, stderr, seconds)."""
    code = ("import sys, time, json, xpbd_bench as xb\nt = time.perf_counter()\nruns = xb.read(sys.argv[1])\n"
            "print(json.dumps([time.perf_counter() - t, [r['name'] for r in runs]]))\n")
    p = subprocess.run([sys.executable, "-c", code, path], capture_output=True, text=True, env=env(), cwd=cwd)
    if p.returncode != 0:
        return p.returncode, [], p.stderr, 0.0
    took, names = json.loads(p.stdout.splitlines()[-1])
    return 0, names, p.stderr, took


def stopped_writer(binary, work):
    """SIGSTOP before the link of the run file (step 2: after its flush), the lock held."""
    case = "a writer stopped inside its commit"
    out = os.path.join(work, "stopped", "r.h5")
    os.makedirs(os.path.dirname(out))
    assert xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs,cholmod", "--out", out])[0] == 0
    t = time.perf_counter()
    xb(binary, ["report", out])
    quiet = time.perf_counter() - t
    p = subprocess.Popen([binary, "run"] + TINY + ["--solver", "cg", "--out", out, "--append", "--quiet"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env({"XB_FAULT_SIGNAL": "2:SIGSTOP"}))
    try:
        if not wait_stopped(p):
            fail(case, "the writer did not stop")
            return
        t = time.perf_counter()
        rc, _, err = xb(binary, ["report", out], timeout=60)
        took = time.perf_counter() - t
        if rc != 0 or took > quiet + 1.0:
            fail(case, f"report: exit {rc} after {took:.2f} s (without the writer {quiet:.2f} s): {err}")
        t = time.perf_counter()
        names, skipped = read_names(out)
        loaded = time.perf_counter() - t
        if len(names) != 2 or skipped or loaded > 1.0:
            fail(case, f"the plots' loader: {names}, {skipped} after {loaded:.2f} s")
        rc, pnames, err, ptook = python_read(out)
        if rc != 0 or len(pnames) != 2 or ptook > 1.0:
            fail(case, f"xpbd_bench.read: exit {rc}, {pnames} after {ptook:.2f} s: {err[-500:]}")
        print(f"{case}: report {took:.2f} s (quiet {quiet:.2f} s), loader {loaded:.3f} s, xpbd_bench.read {ptook:.3f} s",
              flush=True)
    finally:
        p.send_signal(signal.SIGCONT)
        _, err = p.communicate(timeout=600)
    if p.returncode != 0 or len(read_names(out)[0]) != 3:
        fail(case, f"the writer, continued, exited {p.returncode}: {err[-500:]}")


def readable_everywhere(case, binary, path, cwd, count):
    rc, text, err = xb(binary, ["report", path, "--format", "json"], cwd=cwd)
    if rc != 0 or len(json.loads(text or "[]")) != count:
        fail(case, f"report from {cwd}: exit {rc}: {err[-500:]}")
    here = os.getcwd()
    os.chdir(cwd)
    try:
        names, skipped = read_names(path)
    finally:
        os.chdir(here)
    if len(names) != count or skipped:
        fail(case, f"the plots' loader from {cwd}: {names} {skipped}")
    rc, names, err, _ = python_read(path, cwd=cwd)
    if rc != 0 or len(names) != count or "skipped" in err:
        fail(case, f"xpbd_bench.read from {cwd}: exit {rc}, {names}: {err[-500:]}")


def h5py_reads(case, path, cwd, count):
    here = os.getcwd()
    os.chdir(cwd)
    try:
        with h5py.File(path, "r") as f:
            got = sum("status" in g.attrs for g in f["runs"].values())
    except (KeyError, OSError) as e:
        got = f"{e!r}"
    finally:
        os.chdir(here)
    if got != count:
        fail(case, f"h5py from {cwd}: {got} runs, expected {count}")


def moved_files(binary, work):
    case = "renamed, copied, symlinked"
    top = os.path.join(work, "moved")
    elsewhere = os.path.join(top, "elsewhere")
    os.makedirs(elsewhere)
    r = os.path.join(top, "r.h5")
    assert xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs,cholmod", "--out", r])[0] == 0
    s = os.path.join(top, "s.h5")
    os.rename(r, s)
    os.rename(r + ".runs", s + ".runs")
    readable_everywhere(case + ": renamed", binary, s, elsewhere, 2)
    assert xb(binary, ["repair", s])[0] == 0
    h5py_reads(case + ": renamed, after repair", s, elsewhere, 2)
    copy = os.path.join(top, "copy")
    os.makedirs(copy)
    shutil.copy(s, os.path.join(copy, "s.h5"))
    shutil.copytree(s + ".runs", os.path.join(copy, "s.h5.runs"))
    readable_everywhere(case + ": copied", binary, os.path.join(copy, "s.h5"), elsewhere, 2)
    h5py_reads(case + ": copied", os.path.join(copy, "s.h5"), elsewhere, 2)
    os.makedirs(os.path.join(top, "real"))
    link = os.path.join(top, "link.h5")
    os.symlink("real/t.h5", link)
    for _ in range(2):
        rc, _, err = xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs", "--out", link, "--append"], cwd=elsewhere)
        if rc != 0:
            fail(case + ": symlinked --out", f"exit {rc}: {err[-500:]}")
    if not os.path.islink(link) or not os.path.isdir(os.path.join(top, "real", "t.h5.runs")):
        fail(case + ": symlinked --out", "the link was replaced, or the runs are not beside the file it points to")
    readable_everywhere(case + ": symlinked --out", binary, link, elsewhere, 2)
    h5py_reads(case + ": symlinked --out, the file itself", os.path.join(top, "real", "t.h5"), elsewhere, 2)
    print(f"{case}: read from another folder by report, the plots' loader and xpbd_bench.read", flush=True)


def neighbour_untouched(binary, work):
    case = "a run beside a 1,000-run file"
    folder = os.path.join(work, "neighbour")
    os.makedirs(folder)
    big = build_results_store.build(binary, 1000, os.path.join(folder, "big.h5"))
    if len(read_names(big)[0]) != 1000:
        fail(case, "the built file does not hold 1000 runs")
    stat = {p: (os.stat(p).st_mtime_ns, os.stat(p).st_size) for p in
            [big] + [os.path.join(d, n) for d, _, ns in os.walk(big + ".runs") for n in ns]}
    before = snapshot(big)
    rc, _, err = xb(binary, ["run"] + TINY + ["--solver", "xpbd-gs", "--out", os.path.join(folder, "new.h5")])
    if rc != 0:
        fail(case, f"exit {rc}: {err[-500:]}")
    after = {p: (os.stat(p).st_mtime_ns, os.stat(p).st_size) for p in stat if os.path.exists(p)}
    if after != stat or snapshot(big) != before:
        fail(case, "the 1,000-run file changed")
    # Not opened, not listed, not looked at: no path of it in any file call of the command.
    said = "untouched"
    if shutil.which("strace"):
        log = os.path.join(folder, "strace.log")
        p = subprocess.run(["strace", "-f", "-e", "trace=%file", "-o", log, binary, "run"] + TINY +
                           ["--solver", "xpbd-gs", "--out", os.path.join(folder, "other.h5"), "--quiet"],
                           capture_output=True, text=True, env=env())
        with open(log) as fh:
            touched = [ln for ln in fh if "big.h5" in ln]
        if p.returncode != 0 or touched:
            fail(case, f"exit {p.returncode}; file calls naming it: {touched[:5]}")
        said += ", and no file call of the run names it (strace)"
    print(f"{case}: {said}", flush=True)


TESTS = [locks_fail, identical_sweeps, damaged_runs, stopped_writer, moved_files, neighbour_untouched]

if __name__ == "__main__":
    sys.exit(run_tests(TESTS, __doc__))
