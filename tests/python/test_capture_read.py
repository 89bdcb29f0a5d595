"""capture's matrices are the Matrix Market files it writes and A = J M⁻¹Jᵀ + α̃ (K = M + Jᵀα̃⁻¹J on
the free particles); read() agrees with `report --format json`; the lists are the CLI's."""
import json
import math
import subprocess

import numpy as np
import scipy.io
import scipy.sparse as sp

import xpbd_bench as xb
from solvers import Splu


def test_capture_equals_its_files_and_the_forms(tmp_path):
    s = xb.capture("cloth_hang", frame=1, iteration=0, set={"resolution": 8}, out=tmp_path / "c")
    assert s.path == str(tmp_path / "c.h5") and s.attrs["frame"] == 1
    # Matrix Market keeps the lower triangle (17 digits: bit for bit); b and f as they are.
    for name, M in (("A", s.A), ("K", s.K)):
        F = scipy.io.mmread(tmp_path / f"c_{name}.mtx").tocsr()
        assert F.shape == M.shape
        assert abs(sp.tril(F) - sp.tril(M)).max() == 0
    for name, v in (("b", s.b), ("f", s.f)):
        np.testing.assert_array_equal(scipy.io.mmread(tmp_path / f"c_{name}.mtx").ravel(), v)
    minv = sp.diags(np.repeat(s.inv_mass, 3))
    A = s.J @ minv @ s.J.T + sp.diags(s.alpha_tilde)
    assert abs(A - s.A).max() <= 1e-12 * abs(s.A).max()
    cols = (3 * s.free_particles[:, None] + np.arange(3)).ravel()
    Jf = s.J[:, cols]
    K = sp.diags(np.repeat(1 / s.inv_mass[s.free_particles], 3)) + Jf.T @ sp.diags(1 / s.alpha_tilde) @ Jf
    assert abs(K - s.K).max() <= 1e-12 * abs(s.K).max()
    np.testing.assert_allclose(s.f, Jf.T @ (s.b / s.alpha_tilde), rtol=1e-12, atol=1e-12 * abs(s.f).max())
    # The rigid modes: translations are unit vectors per axis; rotations e_k x (p - centroid).
    assert s.rigid_modes.shape == (s.K.shape[0], 6)
    np.testing.assert_array_equal(s.rigid_modes[:, :3], np.tile(np.eye(3), (len(s.free_particles), 1)))
    p = s.positions[s.free_particles]
    np.testing.assert_allclose(s.rigid_modes[:, 3].reshape(-1, 3), np.cross([1, 0, 0], p - p.mean(axis=0)), atol=1e-12)


def test_read_agrees_with_report_json(tmp_path, bench):
    out = tmp_path / "r.h5"
    runs = xb.run("cloth_hang", solvers=["xpbd-gs", Splu()], out=out, frames=1, set={"resolution": 8})
    report = json.loads(subprocess.run([bench, "report", str(out), "--format", "json"], capture_output=True,
                                       text=True, check=True).stdout)
    assert [r["run"] for r in report] == [r["name"] for r in runs]
    for j, r in zip(report, runs):
        j.pop("run")
        j.pop("timing_note", None)  # report's own judgement of the timings, not attributes
        j.pop("timing_suspect")
        assert set(j) == set(r["attrs"])
        for k, v in r["attrs"].items():
            if isinstance(v, float) and not math.isfinite(v):
                assert j[k] is None
            else:
                assert j[k] == v, k
        assert len(r["data"]["relative_dual_residual"]) == r["attrs"]["outer_iterations"] + 1


def test_lists_are_the_cli_list(bench):
    text = subprocess.run([bench, "list"], capture_output=True, text=True, check=True).stdout
    assert all(f"  {s}\n" in text for s in xb.scenes())
    assert all(f"  {s['name']}  [{s['kind']}]" in text for s in xb.solvers() if s["name"] != "py:mgpbd-gpu")
    assert all(f"  {p['key']} = {p['default']}: " in text for p in xb.parameters())
