"""python/xpbd_bench/device_parts.py, how scripts/gpu_check.sh packs its captures: the tree it
measures is what a device call carries (tracked and untracked-not-ignored files, shared/; not the
ignored ones), each part fits beside it within the limit, and the parts join into the file."""
import os
import subprocess
import sys

import pytest

from xpbd_bench import device_parts as dp

MIB = dp.MIB


def make_tree(root):
    subprocess.run(["git", "init", "-q", str(root)], check=True)
    (root / ".gitignore").write_text("ignored/\n")
    (root / "tracked.bin").write_bytes(b"t" * (3 * MIB))
    subprocess.run(["git", "-C", str(root), "add", "tracked.bin", ".gitignore"], check=True)
    (root / "untracked.bin").write_bytes(b"u" * MIB)        # not ignored: it travels
    (root / "ignored").mkdir()
    (root / "ignored" / "big.bin").write_bytes(b"i" * (10 * MIB))  # ignored: it does not
    (root / "shared").mkdir()
    (root / "shared" / "notes.md").write_bytes(b"s" * (MIB // 2))
    return 3 * MIB + MIB + MIB // 2 + len("ignored/\n")


def test_tree_bytes_counts_what_travels(tmp_path):
    expected = make_tree(tmp_path)
    assert dp.tree_bytes(str(tmp_path)) == expected


def test_every_part_fits_beside_the_tree(tmp_path):
    (tmp_path / "repo").mkdir()
    tree = make_tree(tmp_path / "repo")
    src = tmp_path / "captures.tar"
    payload = os.urandom(3 * MIB + 12345)
    src.write_bytes(payload)
    limit = 8 * MIB  # a small limit: the same arithmetic as 64 MiB, with small files
    out = tmp_path / "parts"
    r = subprocess.run([sys.executable, "-m", "xpbd_bench.device_parts", "split", str(src), str(out), "--root",
                        str(tmp_path / "repo"), "--limit-mib", "8", "--margin-mib", "2"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    parts = sorted(out.glob("*/chunk"))
    assert [p.parent.name for p in parts] == [f"{k:02d}" for k in range(len(parts))] and len(parts) == 4
    assert all(p.stat().st_size + tree + 2 * MIB <= limit for p in parts)
    assert parts[0].stat().st_size == MIB  # the whole MiB left: 8 - 4.5 - 2, rounded down
    assert b"".join(p.read_bytes() for p in parts) == payload
    # The old fixed 60 MiB parts would not fit beside this tree within 64 MiB; the sized ones do.
    assert dp.part_bytes(tree) + tree <= 64 * MIB < 60 * MIB + tree + 2 * MIB


def test_a_tree_too_big_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="no room"):
        dp.part_bytes(63 * MIB)
    src = tmp_path / "f"
    src.write_bytes(b"x")
    (tmp_path / "repo").mkdir()
    make_tree(tmp_path / "repo")
    r = subprocess.run([sys.executable, "-m", "xpbd_bench.device_parts", "split", str(src), str(tmp_path / "p"),
                        "--root", str(tmp_path / "repo"), "--limit-mib", "6"], capture_output=True, text=True)
    assert r.returncode == 1 and "no room" in r.stderr and not (tmp_path / "p").exists()
