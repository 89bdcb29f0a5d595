#!/usr/bin/env python3
"""A full disk through the CLI (issue 33; docs/failures.md): run, solve, sweep and capture each
meet a write that fails at the first write call of an append, in the middle of the run's file, at
the index's last write and flush, and at the rename of either (an append writes the run's file in
FILE.runs/ and then the index FILE: harness/io/recorder.hpp; the fault hook XB_FAULT_WRITE /
XB_FAULT_RENAME of harness/io/io_fault.hpp). Every case must end with exit code 2, one line naming
the file and the cause in words, the earlier file (index and run files) byte-for-byte as it was,
no .tmp left and no signal; a sweep or a run of several solvers keeps the runs it finished. Then
the same commands on a real 300 KB tmpfs, when this machine lets us mount one (root); skipped
with a message where not.

    python3 tests/harness/cli/test_disk_full.py --binary build/xpbd-bench
"""
import argparse
import concurrent.futures
import os
import shutil
import subprocess
import sys
import tempfile

CHUNK = 16384  # write_chunk of harness/io/atomic_file.hpp: a file of S bytes is ceil(S/CHUNK) writes + 1 fsync
FAILURES = []


def calls(size):
    return -(-size // CHUNK) + 1


def read(path):
    with open(path, "rb") as f:
        return f.read()


def snapshot(path):
    """A results file as the user sees it: the index and every file of its runs folder (not the
    lock), by name; None when absent."""
    if not os.path.exists(path):
        return None
    files = {"index": read(path)}
    for d, _, names in os.walk(path + ".runs"):  # the runs folder and its store
        files.update({f: read(os.path.join(d, f)) for f in names if f != "lock"})
    return files


def copy_results(src, folder):
    """The index and its runs folder into `folder`, under the same name (the links name it)."""
    dst = os.path.join(folder, os.path.basename(src))
    shutil.copy(src, dst)
    if os.path.isdir(src + ".runs"):
        shutil.copytree(src + ".runs", dst + ".runs")
    return dst


def new_run_file(before, after):
    """The size of the run file an append added (in `after`'s snapshot, not in `before`'s)."""
    added = [k for k in after if k != "index" and k not in (before or {})]
    assert len(added) == 1, f"expected one new run file, got {added}"
    return len(after[added[0]])


def xb(binary, args, env=None, cwd=None):
    e = dict(os.environ, OMP_NUM_THREADS="1")
    e.update(env or {})
    p = subprocess.run([binary] + args + ["--quiet"], capture_output=True, text=True, env=e, cwd=cwd, timeout=300)
    return p.returncode, p.stderr


def fail(case, why):
    FAILURES.append(f"{case}: {why}")


def check_failed(case, rc, err, target, before, words, kept=None, named=None):
    """Exit 2, one error line naming the file (`named`, else target) and words, target (a snapshot,
    or the bytes of a capture's file) unchanged, no .tmp beside it. Returns the error line."""
    lines = [ln for ln in err.splitlines() if ln.startswith("xpbd-bench:")]
    named = named or target
    if rc != 2:
        fail(case, f"exit code {rc}, expected 2; stderr:\n{err}")
    if len(lines) != 1:
        fail(case, f"expected one error line, got {lines}; stderr:\n{err}")
    elif "cannot " not in lines[0] or named not in lines[0]:
        fail(case, f"the error does not name {named}: {lines[0]}")
    elif words not in lines[0]:
        fail(case, f"the error does not say '{words}': {lines[0]}")
    elif kept is not None and kept not in lines[0]:
        fail(case, f"the error does not say '{kept}': {lines[0]}")
    now = read(target) if isinstance(before, bytes) else snapshot(target)
    if os.path.exists(target) and now != before:
        fail(case, f"{target} changed")
    folder = os.path.dirname(target)
    left = [f for _, _, files in os.walk(folder) for f in files if f.endswith(".tmp")]
    if left:
        fail(case, f".tmp left behind: {left}")
    return lines[0] if lines else ""


def faults(run_size, index_size):
    """(name, environment) for an append of a run file of run_size bytes and an index of
    index_size: the first write, the middle of the run file, the index's last write and its flush,
    the run file's rename and the index's."""
    r, n = calls(run_size), calls(run_size) + calls(index_size)
    assert r >= 4, f"a run file of {run_size} bytes is too small to have a middle write"
    return [("first write", {"XB_FAULT_WRITE": "1:ENOSPC"}, "no space left on device"),
            ("middle write", {"XB_FAULT_WRITE": f"{r // 2}:EFBIG"}, "file too large"),
            ("last write", {"XB_FAULT_WRITE": f"{n - 1}:ENOSPC"}, "no space left on device"),
            ("flush", {"XB_FAULT_WRITE": f"{n}:ENOSPC"}, "no space left on device"),
            ("rename of the run file", {"XB_FAULT_RENAME": "1:EROFS"}, "read-only file system"),
            ("rename of the index", {"XB_FAULT_RENAME": "2:EROFS"}, "read-only file system")]


def command_cases(binary, work):
    """Each command against each fault: a list of (case, thunk) run in parallel."""
    run = ["run", "--scene", "cloth_hang", "--set", "resolution=8", "--frames", "2", "--solver", "mgpbd"]
    os.makedirs(os.path.join(work, "earlier"))
    earlier = os.path.join(work, "earlier", "F.h5")
    assert xb(binary, ["run", "--scene", "cloth_hang", "--set", "resolution=8", "--frames", "1", "--solver", "cholmod",
                       "--out", earlier])[0] == 0
    system = os.path.join(work, "sys")
    assert xb(binary, ["capture", "--scene", "cloth_hang", "--set", "resolution=24", "--frame", "0", "--iteration", "0",
                       "--out", system])[0] == 0
    solve = ["solve", "--system", system + ".h5", "--solver", "cg"]
    spec = os.path.join(work, "sweep.toml")
    with open(spec, "w") as f:
        f.write('scene = "cloth_hang"\nsolvers = ["mgpbd"]\nframes = 2\n[set]\nresolution = 8\n'
                '[grid]\ncompliance = [1e-8, 1e-6, 1e-4]\n')
    sweep = ["sweep", spec]
    cases = []
    for name, args in (("run", run), ("solve", solve), ("sweep", sweep)):
        probe = copy_results(earlier, tempfile.mkdtemp(dir=work))  # a sweep appends to it; run and solve replace it
        # The files the first append makes: for the sweep, stop before its second append.
        rc, err = xb(binary, args + ["--out", probe], {"XB_FAULT_RENAME": "3:EIO"} if name == "sweep" else None)
        if rc != (2 if name == "sweep" else 0):
            fail(f"{name} probe", f"exit {rc} (is XB_FAULT_RENAME honoured?): {err}")
        after = snapshot(probe)
        for fault, env, words in faults(new_run_file(snapshot(earlier), after), len(after["index"])):
            case = f"{name} at the {fault}"
            cases.append((case, lambda c=case, a=args, e=env, w=words: one_case(binary, work, c, a, earlier, e, w)))
    # Runs finished before the failed write stay: a run of two solvers, a sweep of three runs.
    cases.append(("run of two solvers, second write fails",
                  lambda: kept_case(binary, work, run[:-1] + ["cholmod,mgpbd"], earlier, "it holds the 1 run finished before")))
    cases.append(("sweep, second write fails",
                  lambda: kept_case(binary, work, sweep, earlier, "it holds the 2 runs finished before")))
    cases += capture_cases(binary, work)
    cases += [(f"run {flag}", lambda f=flag, n=named: side_file_case(binary, work, run, f, n))
              for flag, named in (("--write-meshes", "cloth_hang_mgpbd_0000.ply"), ("--save-state", "state.h5"))]
    return cases


def side_file_case(binary, work, run, flag, named):
    """A mesh or state that cannot be written ends the command too (the stepper would make it a
    run with status error and go on)."""
    folder = tempfile.mkdtemp(dir=work)
    out = os.path.join(folder, "F.h5")
    side = os.path.join(folder, "meshes" if flag == "--write-meshes" else "state.h5")
    extra = [flag, side] + (["--frame-of-state", "0"] if flag == "--save-state" else [])
    rc, err = xb(binary, run + extra + ["--out", out], {"XB_FAULT_WRITE": "1:ENOSPC"})
    check_failed(f"run {flag}", rc, err, out, None, "no space left on device", named=named)
    if os.path.exists(out):
        fail(f"run {flag}", "the run was recorded after its mesh or state failed")


def one_case(binary, work, case, args, earlier, env, words):
    out = copy_results(earlier, tempfile.mkdtemp(dir=work))
    rc, err = xb(binary, args + ["--out", out], env)
    check_failed(case, rc, err, out, snapshot(earlier), words)


def kept_case(binary, work, args, earlier, kept):
    out = copy_results(earlier, tempfile.mkdtemp(dir=work))
    # The second append's first rename (its run file's; each append renames two files).
    rc, err = xb(binary, args + ["--out", out], {"XB_FAULT_RENAME": "3:ENOSPC"})
    case = " ".join(args[:1]) + " keeps its finished runs"
    # The file is not the earlier one any more: it holds the first run(s); it is what the failed
    # write found, so check it is readable and holds them.
    check_failed(case, rc, err, out, snapshot(out), "no space left on device", kept)
    if subprocess.run([binary, "report", out], capture_output=True).returncode != 0:
        fail(case, "the kept runs cannot be reported")
    if args[0] == "sweep":  # and resumes
        rc, err = xb(binary, args + ["--out", out])
        if rc != 0 or "(1 already in" not in err:
            fail(case, f"the rerun did not resume (exit {rc}): {err}")


def capture_cases(binary, work):
    args = ["capture", "--scene", "cloth_hang", "--set", "resolution=8", "--frame", "0", "--iteration", "0"]
    earlier = os.path.join(work, "cap_earlier")
    assert xb(binary, args[:4] + ["resolution=6"] + args[5:] + ["--out", earlier])[0] == 0  # other bytes
    probe = os.path.join(work, "cap_probe")
    assert xb(binary, args + ["--out", probe])[0] == 0
    suffixes = [".h5", "_A.mtx", "_b.mtx", "_K.mtx", "_f.mtx"]
    n = sum(calls(os.path.getsize(probe + s)) for s in suffixes)
    cases = []
    for fault, env, words in [("first write", {"XB_FAULT_WRITE": "1:ENOSPC"}, "no space left on device"),
                              ("middle write", {"XB_FAULT_WRITE": f"{n // 2}:EFBIG"}, "file too large"),
                              ("last write", {"XB_FAULT_WRITE": f"{n - 1}:ENOSPC"}, "no space left on device"),
                              ("flush", {"XB_FAULT_WRITE": f"{n}:ENOSPC"}, "no space left on device"),
                              ("first rename", {"XB_FAULT_RENAME": "1:EROFS"}, "read-only file system"),
                              ("rename of the .h5", {"XB_FAULT_RENAME": "5:EROFS"}, "read-only file system")]:
        def go(fault=fault, env=env, words=words):
            folder = tempfile.mkdtemp(dir=work)
            prefix = os.path.join(folder, "P")
            for s in suffixes:
                shutil.copy(earlier + s, prefix + s)
            rc, err = xb(binary, args + ["--out", prefix], env)
            case = f"capture at the {fault}"
            # The .h5 (renamed last) is the earlier one after every fault; the line names the
            # file that failed, one of P's.
            line = check_failed(case, rc, err, prefix + ".h5", read(earlier + ".h5"), words, named=prefix)
            replaced = "rename of the .h5" in fault
            if ("already replaced: " + prefix + "_A.mtx" if replaced else "no file of " + prefix + " was replaced") not in line:
                fail(case, f"the error does not say which files were replaced: {line}")
            for s in ([] if replaced else suffixes):
                if read(prefix + s) != read(earlier + s):
                    fail(case, f"P{s} changed")
        cases.append((f"capture at the {fault}", go))
    return cases


def real_full_disk(binary, work):
    """The commands of issue 33's table on a 300 KB tmpfs holding an earlier file and a filler."""
    mnt = os.path.join(work, "small_fs")
    os.makedirs(mnt)
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", mnt], capture_output=True, text=True)
    if p.returncode != 0:
        print(f"test_disk_full: SKIPPED the real full disk: cannot mount a tmpfs here ({p.stderr.strip() or p.returncode})")
        return
    try:
        system = os.path.join(work, "sys.h5")
        spec = os.path.join(work, "sweep.toml")
        commands = {
            "run": ["run", "--scene", "cloth_hang", "--set", "resolution=64", "--frames", "3", "--solver", "cholmod,mgpbd"],
            "solve": ["solve", "--system", system, "--solver", "cholmod,cg,mgpbd"],
            "sweep": ["sweep", spec],
            "capture": ["capture", "--scene", "cloth_hang", "--set", "resolution=32", "--frame", "0", "--iteration", "0"],
        }
        for name, args in commands.items():
            for f in os.listdir(mnt):
                shutil.rmtree(os.path.join(mnt, f)) if os.path.isdir(os.path.join(mnt, f)) else os.remove(os.path.join(mnt, f))
            out = os.path.join(mnt, "F.h5")
            assert xb(binary, ["run", "--scene", "cloth_hang", "--set", "resolution=8", "--frames", "1", "--solver",
                               "cholmod", "--out", out])[0] == 0
            # Leave room for about one run (an append writes the run's file and the index, ~45 KB
            # here), so that the first write fits or not and a later one surely does not.
            st = os.statvfs(mnt)
            with open(os.path.join(mnt, "filler"), "wb") as f:
                f.write(b"\0" * max(0, st.f_bavail * st.f_frsize - {"sweep": 70_000, "solve": 50_000}.get(name, 40_000)))
            before = snapshot(out)
            target = os.path.join(mnt, "P") if name == "capture" else out
            rc, err = xb(binary, args + ["--out", target])
            case = f"real full disk: {name}"
            lines = [ln for ln in err.splitlines() if ln.startswith("xpbd-bench:")]
            print(f"{case}: exit {rc}: {lines[0] if lines else err.strip()[-200:]}")
            if rc != 2 or len(lines) != 1 or "no space left on device" not in lines[0]:
                fail(case, f"exit {rc}, expected 2 and one line saying 'no space left on device'; stderr:\n{err}")
            if lines and "finished before" not in lines[0] and snapshot(out) != before:
                fail(case, "the earlier F.h5 changed")
            if subprocess.run([binary, "report", out], capture_output=True).returncode != 0:
                fail(case, "F.h5 cannot be reported")
            if [f for _, _, files in os.walk(mnt) for f in files if f.endswith(".tmp")]:
                fail(case, ".tmp left behind")
    finally:
        subprocess.run(["umount", mnt], check=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--jobs", type=int, default=2 * (os.cpu_count() or 1))
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    with tempfile.TemporaryDirectory(prefix="xb_disk_full_") as work:
        cases = command_cases(binary, work)
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            for (case, _), fut in zip(cases, [pool.submit(fn) for _, fn in cases]):
                try:
                    fut.result()
                except Exception as e:  # a broken case is a failure, not a crash of the test
                    fail(case, repr(e))
        real_full_disk(binary, work)
    for f in FAILURES:
        print("FAIL", f)
    print(f"test_disk_full: {len(cases)} fault cases, {len(FAILURES)} failures")
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
