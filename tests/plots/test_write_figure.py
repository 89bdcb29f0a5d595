"""The plots' writer (plots/xbruns.py write_figure): a figure is written whole or not at
all. A failed write, flush or rename (a full disk) ends the script with one line naming the file
and the cause in words and exit code 2, the earlier file byte-for-byte as it was and no .tmp; on a
real 300 KB tmpfs too, where this machine lets us mount one."""
import errno
import os
import shutil
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import xbruns  # noqa: E402


def figure():
    fig, ax = plt.subplots()
    ax.plot(range(100), [i * i for i in range(100)])
    return fig


def fail_savefig(fig, monkeypatch):
    real = fig.savefig

    def savefig(fh, **kw):  # half the image reaches the file, then the device is full
        real(fh, **kw)
        fh.truncate(fh.tell() // 2)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(fig, "savefig", savefig)


def fail_fsync(fig, monkeypatch):
    def fsync(fd):
        raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))
    monkeypatch.setattr(xbruns.os, "fsync", fsync)


def fail_rename(fig, monkeypatch):
    def replace(a, b):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))
    monkeypatch.setattr(xbruns.os, "replace", replace)


@pytest.mark.parametrize("fault,words", [(fail_savefig, "no space left on device"), (fail_fsync, "file too large"),
                                         (fail_rename, "read-only file system")])
def test_a_failed_write_exits_2_and_leaves_the_earlier_file(tmp_path, monkeypatch, capsys, fault, words):
    out = tmp_path / "fig.png"
    out.write_bytes(b"the earlier figure")
    fig = figure()
    fault(fig, monkeypatch)
    with pytest.raises(SystemExit) as e:
        xbruns.write_figure(fig, str(out), dpi=50)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"cannot write {out}: {words}" in err, err
    assert out.read_bytes() == b"the earlier figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]


def test_a_figure_is_written_whole(tmp_path):
    out = tmp_path / "sub" / "fig.png"
    xbruns.save(figure(), str(out))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "sub" / "fig.pdf").read_bytes()[:5] == b"%PDF-"
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["fig.pdf", "fig.png"]


def test_a_real_full_disk(tmp_path):
    bench = os.environ.get("XB_BENCH", os.path.join(ROOT, "build", "xpbd-bench"))
    results = tmp_path / "r.h5"
    r = subprocess.run([bench, "run", "--scene", "cloth_hang", "--set", "resolution=8", "--solver", "cholmod",
                        "--out", str(results), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    mnt = tmp_path / "small_fs"
    mnt.mkdir()
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(mnt)], capture_output=True, text=True)
    if m.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({m.stderr.strip() or m.returncode})")
    try:
        out = mnt / "conv.png"
        out.write_bytes(b"the earlier figure")
        (mnt / "filler").write_bytes(b"\0" * 270_000)
        p = subprocess.run([sys.executable, os.path.join(ROOT, "plots", "convergence.py"), str(results), "-o", str(out)],
                           capture_output=True, text=True)
        assert p.returncode == 2, p.stderr
        assert f"cannot write {out}: no space left on device" in p.stderr.strip().splitlines()[-1], p.stderr
        assert out.read_bytes() == b"the earlier figure"
        assert sorted(os.listdir(mnt)) == ["conv.png", "filler"]
    finally:
        subprocess.run(["umount", str(mnt)], check=False)
        shutil.rmtree(mnt, ignore_errors=True)
