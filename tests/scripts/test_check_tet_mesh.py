"""scripts/check_tet_mesh.py, the check get_meshes.sh runs on every mesh it writes: a cube of 6
tets passes; a flipped tet, a flat tet, an unused vertex, two tets meeting at an edge only (a
boundary edge in four faces) and a truncated file each fail with their own message."""
import importlib.util
import os
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SCRIPT = os.path.join(ROOT, "scripts", "check_tet_mesh.py")
spec = importlib.util.spec_from_file_location("check_tet_mesh", SCRIPT)
ctm = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ctm)

CUBE_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]  # vertex 4x + 2y + z
# The Kuhn decomposition of the unit cube along the diagonal 0-7: 6 positive tets.
CUBE_T = [(0, 4, 6, 7), (0, 4, 7, 5), (0, 1, 5, 7), (0, 1, 7, 3), (0, 2, 3, 7), (0, 2, 7, 6)]


def write(tmp_path, V, T, first=0, nt=None):
    node, ele = tmp_path / "m.node", tmp_path / "m.ele"
    node.write_text(f"{len(V)} 3 0 0\n" + "".join(f"{i + first} {x} {y} {z}\n" for i, (x, y, z) in enumerate(V)))
    ele.write_text(f"{len(T) if nt is None else nt} 4 0\n# a comment\n" +
                   "".join(f"{i + first} " + " ".join(str(v + first) for v in t) + "\n" for i, t in enumerate(T)))
    return str(node), str(ele)


def test_the_cube_is_valid_in_both_numberings(tmp_path):
    for first in (0, 1):
        summary = ctm.check(*write(tmp_path, CUBE_V, CUBE_T, first))
        assert summary.startswith("6 tets, 8 vertices, 12 boundary faces") and "volume 1" in summary
    flipped = [(a, c, b, d) for a, b, c, d in CUBE_T]  # the other orientation, for all: valid
    ctm.check(*write(tmp_path, CUBE_V, flipped))


@pytest.mark.parametrize("case, V, T, nt, message", [
    ("one flipped", CUBE_V, [(0, 6, 4, 7)] + CUBE_T[1:], None, "not one orientation"),
    ("flat", CUBE_V + [(0.5, 0, 0)], CUBE_T + [(0, 8, 4, 1)], None, "flat"),
    ("unused vertex", CUBE_V + [(2, 2, 2)], CUBE_T, None, "in no tet"),
    ("edge only", [(0, 0, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, -1, 0)],
     [(0, 2, 3, 1), (0, 4, 5, 1)], None, "not closed"),
    ("truncated", CUBE_V, CUBE_T[:5], 6, "headers say"),
])
def test_an_invalid_mesh_is_named(tmp_path, case, V, T, nt, message):
    with pytest.raises(ValueError, match=message):
        ctm.check(*write(tmp_path, V, T, nt=nt))
    r = subprocess.run([sys.executable, SCRIPT, *write(tmp_path, V, T, nt=nt)], capture_output=True, text=True)
    assert r.returncode == 1 and message in r.stderr, (case, r.stderr)
