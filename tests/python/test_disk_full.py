"""A full disk through the Python package (issue 33; docs/failures.md): xb.run, xb.solve and
xb.capture against a write failing at the first write of an append, in the middle of the run's
file, at the index's last write and flush, and at either rename (an append writes the run's file
in FILE.runs/, then the index FILE; XB_FAULT_WRITE / XB_FAULT_RENAME, read once per process, so
each case is its own interpreter). Each must raise xpbd_bench.WriteError (an xpbd_bench.Error and
an OSError with errno and filename) with the one-line message, leave the earlier file (index and
run files) byte-for-byte as it was and no .tmp, and the interpreter must go on (and exit 0,
without a crash at exit). xb.run keeps the runs it finished before a failed write and says so; a
read-only folder is a WriteError naming the caller's file."""
import errno
import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

CHUNK = 16384  # write_chunk of harness/io/atomic_file.hpp: S bytes are ceil(S/CHUNK) writes + 1 fsync

CALLS = {
    "run": "xb.run('cloth_hang', solvers=['mgpbd'], out=OUT, frames=2, set={'resolution': 8})",
    "solve": "xb.solve(SYSTEM, solvers=['cg'], out=OUT)",
}
SCRIPT = """
import json, sys
import xpbd_bench as xb
OUT, SYSTEM = sys.argv[1], sys.argv[2]
try:
    {call}
    print(json.dumps({{"raised": None}}))
except xb.Error as e:
    print(json.dumps({{"raised": type(e).__name__, "message": str(e), "errno": getattr(e, "errno", None),
                      "filename": getattr(e, "filename", None), "oserror": isinstance(e, OSError)}}))
print(json.dumps({{"alive": len(xb.read(OUT))}}))
"""


def calls(size):
    return -(-size // CHUNK) + 1


def read(path):
    with open(path, "rb") as f:
        return f.read()


def snapshot(path):
    """The index and every file of its runs folder (not the lock), by name; None when absent."""
    if not os.path.exists(path):
        return None
    files = {"index": read(path)}
    for d, _, names in os.walk(path + ".runs"):  # the runs folder and its store
        files.update({f: read(os.path.join(d, f)) for f in names if f != "lock"})
    return files


def copy_results(src, folder):
    dst = os.path.join(folder, os.path.basename(src))
    shutil.copy(src, dst)
    if os.path.isdir(src + ".runs"):
        shutil.copytree(src + ".runs", dst + ".runs")
    return dst


def temporaries(folder):
    return [f for _, _, files in os.walk(folder) for f in files if f.endswith(".tmp")]


def python(call, out, system, env=None):
    e = dict(os.environ, OMP_NUM_THREADS="1")
    e.update(env or {})
    p = subprocess.run([sys.executable, "-c", SCRIPT.format(call=call), out, system], capture_output=True, text=True,
                       env=e, timeout=300)
    return p


@pytest.fixture(scope="module")
def work(bench):
    d = tempfile.mkdtemp(prefix="xb_py_disk_full_")
    os.makedirs(os.path.join(d, "earlier"))
    earlier = os.path.join(d, "earlier", "F.h5")
    assert subprocess.run([bench, "run", "--scene", "cloth_hang", "--set", "resolution=8", "--frames", "1",
                           "--solver", "cholmod", "--out", earlier, "--quiet"], capture_output=True).returncode == 0
    system = os.path.join(d, "sys")
    assert subprocess.run([bench, "capture", "--scene", "cloth_hang", "--set", "resolution=24", "--frame", "0",
                           "--iteration", "0", "--out", system, "--quiet"], capture_output=True).returncode == 0
    yield d
    shutil.rmtree(d, ignore_errors=True)


def faults(run_size, index_size):
    r, n = calls(run_size), calls(run_size) + calls(index_size)
    assert r >= 4, f"{run_size} bytes: too small a run file to have a middle write"
    return [({"XB_FAULT_WRITE": "1:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_WRITE": f"{r // 2}:EFBIG"}, errno.EFBIG, "file too large"),
            ({"XB_FAULT_WRITE": f"{n - 1}:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_WRITE": f"{n}:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_RENAME": "1:EROFS"}, errno.EROFS, "read-only file system"),
            ({"XB_FAULT_RENAME": "2:EROFS"}, errno.EROFS, "read-only file system")]


@pytest.mark.parametrize("command", sorted(CALLS))
def test_a_failed_write_raises_and_leaves_the_earlier_file(work, command):
    earlier, system = os.path.join(work, "earlier", "F.h5"), os.path.join(work, "sys.h5")
    probe = copy_results(earlier, tempfile.mkdtemp(dir=work))  # xb.run appends to it, xb.solve replaces it
    p = python(CALLS[command], probe, system)
    assert p.returncode == 0, p.stderr
    before, after = snapshot(earlier), snapshot(probe)
    added = [k for k in after if k != "index" and k not in before]
    assert len(added) == 1, added
    for env, code, words in faults(len(after[added[0]]), len(after["index"])):
        folder = tempfile.mkdtemp(dir=work)
        out = copy_results(earlier, folder)
        p = python(CALLS[command], out, system, env)
        assert p.returncode == 0, f"{env}: the interpreter died ({p.returncode}): {p.stderr}"
        lines = [json.loads(ln) for ln in p.stdout.splitlines() if ln.startswith("{")]
        raised, alive = lines[0], lines[-1]
        assert raised["raised"] == "WriteError", (env, raised)
        assert raised["oserror"] and raised["errno"] == code and raised["filename"] == out, (env, raised)
        assert raised["message"].startswith(f"{command}: cannot ") and out in raised["message"], raised
        assert words in raised["message"] and "\n" not in raised["message"], raised
        assert alive["alive"] == 1, alive  # the earlier file, read after the failure
        assert snapshot(out) == before, f"{env}: {out} changed"
        assert not temporaries(folder), env


def test_a_failed_capture_raises_and_replaces_nothing(work):
    prefix = os.path.join(work, "cap")
    call = "xb.capture('cloth_hang', frame=0, iteration=0, set={'resolution': 8}, out=OUT)"
    p = python(call.replace("OUT", repr(prefix + "_earlier")), os.path.join(work, "earlier", "F.h5"), "")
    assert p.returncode == 0, p.stderr
    for env in ({"XB_FAULT_WRITE": "1:ENOSPC"}, {"XB_FAULT_WRITE": "3:ENOSPC"}, {"XB_FAULT_RENAME": "1:ENOSPC"}):
        folder = tempfile.mkdtemp(dir=work)
        p = python(call.replace("OUT", repr(os.path.join(folder, "P"))), os.path.join(work, "earlier", "F.h5"), "", env)
        assert p.returncode == 0, p.stderr
        raised = json.loads(p.stdout.splitlines()[0])
        assert raised["raised"] == "WriteError" and raised["errno"] == errno.ENOSPC, raised
        assert "no space left on device" in raised["message"] and "was replaced" in raised["message"], raised
        assert os.listdir(folder) == [], f"{env}: left {os.listdir(folder)}"


def test_a_real_full_disk(work):
    mnt = os.path.join(work, "small_fs")
    os.makedirs(mnt)
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", mnt], capture_output=True, text=True)
    if m.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({m.stderr.strip() or m.returncode})")
    try:
        out = copy_results(os.path.join(work, "earlier", "F.h5"), mnt)
        with open(os.path.join(mnt, "filler"), "wb") as f:
            f.write(b"\0" * 150_000)
        before = snapshot(out)
        call = "xb.run('cloth_hang', solvers=['cholmod', 'mgpbd'], out=OUT, frames=3, set={'resolution': 64})"
        p = python(call, out, "")
        assert p.returncode == 0, f"the interpreter died ({p.returncode}): {p.stderr}"
        lines = [json.loads(ln) for ln in p.stdout.splitlines() if ln.startswith("{")]
        raised, alive = lines[0], lines[-1]
        assert raised["raised"] == "WriteError" and "no space left on device" in raised["message"], raised
        # Either nothing fitted (the file as it was) or the first run did, and the message says so.
        if "finished before" in raised["message"]:
            assert "holds the 2 runs finished before" in raised["message"] and alive["alive"] == 2, lines
        else:
            assert snapshot(out) == before
        assert not temporaries(mnt)
    finally:
        subprocess.run(["umount", mnt], check=False)


def test_a_failed_second_write_keeps_the_first_run_and_says_so(work):
    """xb.run appends each run as it ends: when the second cannot be written, the first is in the
    file, and the message says how many runs it holds (the earlier one and this call's first)."""
    out = copy_results(os.path.join(work, "earlier", "F.h5"), tempfile.mkdtemp(dir=work))
    call = "xb.run('cloth_hang', solvers=['xpbd-gs', 'cholmod'], out=OUT, frames=1, set={'resolution': 8})"
    p = python(call, out, "", {"XB_FAULT_RENAME": "3:ENOSPC"})  # the second run's file (two renames a run)
    assert p.returncode == 0, p.stderr
    lines = [json.loads(ln) for ln in p.stdout.splitlines() if ln.startswith("{")]
    raised, alive = lines[0], lines[-1]
    assert raised["raised"] == "WriteError" and raised["filename"] == out, raised
    assert "it holds the 2 runs finished before" in raised["message"], raised
    assert alive["alive"] == 2, lines
    assert not temporaries(os.path.dirname(out))


def test_a_read_only_folder_raises_write_error_naming_the_file(work):
    """A folder that cannot be written: WriteError (not a bare PermissionError) naming the caller's
    path. Root writes anywhere, so as root the folder is a read-only tmpfs mount."""
    folder = os.path.join(work, "read_only")
    os.makedirs(folder)
    if os.geteuid() == 0:
        m = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", folder], capture_output=True, text=True)
        if m.returncode != 0:
            pytest.skip(f"cannot mount a read-only tmpfs here ({m.stderr.strip() or m.returncode})")
    else:
        os.chmod(folder, 0o555)
    try:
        out = os.path.join(folder, "r.h5")
        call = "xb.run('cloth_hang', solvers=['xpbd-gs'], out=OUT, frames=1, set={'resolution': 4})"
        p = python(call, out, "")  # its last line, read(OUT), fails: there is no file
        lines = [json.loads(ln) for ln in p.stdout.splitlines() if ln.startswith("{")]
        assert lines, p.stderr
        raised = lines[0]
        assert raised["raised"] == "WriteError" and raised["oserror"] and raised["filename"] == out, raised
        assert out in raised["message"] and "xpbd_bench_run" not in raised["message"], raised
    finally:
        if os.geteuid() == 0:
            subprocess.run(["umount", folder], check=False)
