"""A full disk through the Python package (issue 33; docs/failures.md): xb.run, xb.solve and
xb.capture against a write failing at the first, a middle and the last write of the file, at its
flush and at its rename (XB_FAULT_WRITE / XB_FAULT_RENAME, read once per process, so each case is
its own interpreter). Each must raise xpbd_bench.WriteError (an xpbd_bench.Error and an OSError
with errno and filename) with the one-line message, leave the earlier file byte-for-byte as it
was and no .tmp, and the interpreter must go on (and exit 0, without a crash at exit)."""
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


def python(call, out, system, env=None):
    e = dict(os.environ, OMP_NUM_THREADS="1")
    e.update(env or {})
    p = subprocess.run([sys.executable, "-c", SCRIPT.format(call=call), out, system], capture_output=True, text=True,
                       env=e, timeout=300)
    return p


@pytest.fixture(scope="module")
def work(bench):
    d = tempfile.mkdtemp(prefix="xb_py_disk_full_")
    earlier = os.path.join(d, "earlier.h5")
    assert subprocess.run([bench, "run", "--scene", "cloth_hang", "--set", "resolution=8", "--frames", "1",
                           "--solver", "cholmod", "--out", earlier, "--quiet"], capture_output=True).returncode == 0
    system = os.path.join(d, "sys")
    assert subprocess.run([bench, "capture", "--scene", "cloth_hang", "--set", "resolution=24", "--frame", "0",
                           "--iteration", "0", "--out", system, "--quiet"], capture_output=True).returncode == 0
    yield d
    shutil.rmtree(d, ignore_errors=True)


def faults(size):
    n = calls(size)
    assert n >= 4, f"{size} bytes: too small a file to have a middle write"
    return [({"XB_FAULT_WRITE": "1:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_WRITE": f"{n // 2}:EFBIG"}, errno.EFBIG, "file too large"),
            ({"XB_FAULT_WRITE": f"{n - 1}:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_WRITE": f"{n}:ENOSPC"}, errno.ENOSPC, "no space left on device"),
            ({"XB_FAULT_RENAME": "1:EROFS"}, errno.EROFS, "read-only file system")]


@pytest.mark.parametrize("command", sorted(CALLS))
def test_a_failed_write_raises_and_leaves_the_earlier_file(work, command):
    earlier, system = os.path.join(work, "earlier.h5"), os.path.join(work, "sys.h5")
    probe = os.path.join(work, f"probe_{command}.h5")
    p = python(CALLS[command], probe, system)
    assert p.returncode == 0, p.stderr
    with open(earlier, "rb") as f:
        before = f.read()
    for env, code, words in faults(os.path.getsize(probe)):
        folder = tempfile.mkdtemp(dir=work)
        out = os.path.join(folder, "F.h5")
        shutil.copy(earlier, out)
        p = python(CALLS[command], out, system, env)
        assert p.returncode == 0, f"{env}: the interpreter died ({p.returncode}): {p.stderr}"
        lines = [json.loads(ln) for ln in p.stdout.splitlines() if ln.startswith("{")]
        raised, alive = lines[0], lines[-1]
        assert raised["raised"] == "WriteError", (env, raised)
        assert raised["oserror"] and raised["errno"] == code and raised["filename"] == out, (env, raised)
        assert raised["message"].startswith(f"{command}: cannot ") and out in raised["message"], raised
        assert words in raised["message"] and "\n" not in raised["message"], raised
        assert alive["alive"] == 1, alive  # the earlier file, read after the failure
        with open(out, "rb") as f:
            assert f.read() == before, f"{env}: {out} changed"
        assert not [f for f in os.listdir(folder) if f.endswith(".tmp")], env


def test_a_failed_capture_raises_and_replaces_nothing(work):
    prefix = os.path.join(work, "cap")
    call = "xb.capture('cloth_hang', frame=0, iteration=0, set={'resolution': 8}, out=OUT)"
    p = python(call.replace("OUT", repr(prefix + "_earlier")), os.path.join(work, "earlier.h5"), "")
    assert p.returncode == 0, p.stderr
    for env in ({"XB_FAULT_WRITE": "1:ENOSPC"}, {"XB_FAULT_WRITE": "3:ENOSPC"}, {"XB_FAULT_RENAME": "1:ENOSPC"}):
        folder = tempfile.mkdtemp(dir=work)
        p = python(call.replace("OUT", repr(os.path.join(folder, "P"))), os.path.join(work, "earlier.h5"), "", env)
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
        out = os.path.join(mnt, "F.h5")
        shutil.copy(os.path.join(work, "earlier.h5"), out)
        with open(os.path.join(mnt, "filler"), "wb") as f:
            f.write(b"\0" * 150_000)
        with open(out, "rb") as f:
            before = f.read()
        call = "xb.run('cloth_hang', solvers=['cholmod', 'mgpbd'], out=OUT, frames=3, set={'resolution': 64})"
        p = python(call, out, "")
        assert p.returncode == 0, f"the interpreter died ({p.returncode}): {p.stderr}"
        raised = json.loads(p.stdout.splitlines()[0])
        assert raised["raised"] == "WriteError" and "no space left on device" in raised["message"], raised
        with open(out, "rb") as f:
            assert f.read() == before
        assert not [f for f in os.listdir(mnt) if f.endswith(".tmp")]
    finally:
        subprocess.run(["umount", mnt], check=False)
