"""The examples run as a user runs them."""
import os
import subprocess
import sys

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "examples")


def run(name, *args):
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_pyamg_solver():
    out = run("pyamg_solver.py", "--set", "resolution=4")
    for form in ("dual", "primal"):
        assert f"squash_mgpbd_{form}" in out and f"squash_py:pyamg-sa_{form}" in out


def test_capture_to_scipy():
    out = run("capture_to_scipy.py")
    assert "A = J M^-1 J^T + alpha~" in out and "K = M + J^T alpha~^-1 J" in out
