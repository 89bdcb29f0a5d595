"""The examples run as a user runs them."""
import os
import subprocess
import sys

import h5py
import numpy as np

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "examples")


def run(name, *args):
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_pyamg_solver(tmp_path):
    """The example's pyamg solver, in both forms, meets the tolerance of every step (each solve's
    dual relative residual, recorded by the harness) and the run its outer tolerance."""
    results = tmp_path / "race.h5"
    out = run("pyamg_solver.py", "--set", "resolution=4", "--out", str(results))
    for form in ("dual", "primal"):
        assert f"squash_mgpbd_{form}" in out and f"squash_py:pyamg-sa_{form}" in out
    with h5py.File(results, "r") as f:
        runs = {name: g for name, g in f["runs"].items() if "py:pyamg-sa" in name}
        assert len(runs) == 2
        for name, g in runs.items():
            assert g.attrs["status"] == "ok", name
            assert g.attrs["relative_dual_residual"] <= g.attrs["rtol"], name
            steps = np.asarray(g["iteration"]) > 0
            reached = np.asarray(g["linear_relative_residual"])[steps]
            asked = np.asarray(g["linear_tolerance"])[steps]
            assert len(reached) > 0 and np.all(reached <= asked * (1 + 1e-9)), (name, reached, asked)


def test_capture_to_scipy():
    out = run("capture_to_scipy.py")
    assert "A = J M^-1 J^T + alpha~" in out and "K = M + J^T alpha~^-1 J" in out
