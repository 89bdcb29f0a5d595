"""The solver protocol inside the harness: a Python direct solver follows cholmod's trajectory in
both forms; a solver that raises, or returns NaN or the wrong shape, is that run's status `error`
with a clear message while the other runs of the call are intact."""
import numpy as np
import pytest

import xpbd_bench as xb
from solvers import Broken, Splu

# A small squash: several outer iterations per substep, both forms exist (every α̃ > 0).
SCENE = {"resolution": 4, "rtol": 1e-6, "max_iterations": 12}


def by_name(runs):
    return {r["name"].split("_", 1)[1]: r for r in runs}


def test_splu_follows_cholmod_in_both_forms(tmp_path):
    splu = Splu()
    # One frame: in a second one the flat start's round-off differences (1e-16) have grown to 1e-7.
    runs = by_name(xb.run("squash", solvers=["cholmod", splu], out=tmp_path / "r.h5", frames=1, set=SCENE,
                          form="dual,primal"))
    for form in ("dual", "primal"):
        ref, py = runs[f"squash_cholmod_{form}"], runs[f"squash_py:splu_{form}"]
        assert py["attrs"]["solver"] == "py:splu" and py["attrs"]["form_used"] == form
        assert py["attrs"]["status"] == ref["attrs"]["status"]
        assert py["attrs"]["outer_iterations"] == ref["attrs"]["outer_iterations"] > 10
        np.testing.assert_allclose(py["data"]["relative_dual_residual"], ref["data"]["relative_dual_residual"],
                                   rtol=1e-8, atol=0)
        # Timed by the harness's clock, setup and solve apart.
        steps = py["data"]["iteration"] > 0
        assert (py["data"]["linear_solve_time"][steps] > 0).all() and (py["data"]["linear_setup_time"][steps] > 0).all()
    dual = [i for i in splu.infos if i["form"] == "dual"]
    primal = [i for i in splu.infos if i["form"] == "primal"]
    assert dual and primal
    assert all(i["block_size"] == 1 and i["near_kernel"] is None for i in dual)
    assert all(i["block_size"] == 3 and i["near_kernel"].shape == (i["shape"][0], 6) for i in primal)
    assert [i["action"] for i in dual[:2]] == ["setup", "refresh"]
    assert {i["frame"] for i in dual} == {0} and [i["iteration"] for i in dual[:3]] == [0, 1, 2]


def test_solve_level_splu_matches_cholmod(tmp_path):
    system = xb.capture("cloth_hang", frame=1, iteration=0, set={"resolution": 8})
    runs = by_name(xb.solve(system, solvers=["cholmod", Splu()], out=tmp_path / "s.h5", form="dual,primal", tol=1e-8))
    for form in ("dual", "primal"):
        py = runs[f"system_py:splu_{form}"]["attrs"]
        assert py["status"] == "ok", py["message"]
        assert py["final_relative_residual"] < 1e-10 and py["error_vs_direct"] < 1e-8
        assert py["setup_time"] > 0 and py["solve_time"] > 0


@pytest.mark.parametrize("how, message", [
    ("solve-raises", "py:broken-solve-raises: solve raised ZeroDivisionError: boom in solve"),
    ("setup-raises", "py:broken-setup-raises: setup raised ValueError: no hierarchy for this matrix"),
    ("nan", "py:broken-nan.solve returned a solution with 1 non-finite entries (NaN or inf)"),
    ("short", "py:broken-short.solve returned an array of shape ("),
    ("column", "py:broken-column.solve returned an array of shape ("),
    ("text", "py:broken-text.solve returned str, not an array of floats"),
    ("iterations", "py:broken-iterations.solve returned (x, iterations) with iterations 2.5, not an int"),
])
def test_a_broken_solver_is_an_error_run_and_the_others_are_intact(tmp_path, how, message):
    out = tmp_path / "r.h5"
    runs = xb.run("squash", solvers=["cholmod", Broken(how), "jacobi-pcg"], out=out, set=SCENE)
    assert [r["attrs"]["status"] for r in runs][1] == "error"
    assert message in runs[1]["attrs"]["message"]
    for r in (runs[0], runs[2]):
        assert r["attrs"]["status"] in ("ok", "max_iterations") and r["attrs"]["outer_iterations"] > 0
        assert len(r["data"]["relative_dual_residual"]) == r["attrs"]["outer_iterations"] + 1


def test_a_broken_solver_at_the_linear_level(tmp_path):
    system = xb.capture("cloth_hang", frame=0, iteration=0, set={"resolution": 8})
    runs = xb.solve(system, solvers=["cholmod", Broken("short"), Broken("solve-raises")], form="dual", out=tmp_path / "s.h5")
    assert [r["attrs"]["status"] for r in runs] == ["ok", "error", "error"]
    n = system.A.shape[0]
    assert f"returned an array of shape ({n - 1},); expected ({n},)" in runs[1]["attrs"]["message"]
    assert "ZeroDivisionError: boom in solve" in runs[2]["attrs"]["message"]
    assert runs[0]["attrs"]["final_relative_residual"] < 1e-10


def test_what_is_not_a_solver_is_refused_before_anything_runs(tmp_path):
    class NoSolve:
        name = "nosolve"

        def setup(self, A, info):
            pass

    with pytest.raises(xb.Error, match="has no method solve"):
        xb.run("squash", solvers=[NoSolve()], out=tmp_path / "r.h5", set=SCENE)
    with pytest.raises(xb.Error, match="non-empty str attribute `name`"):
        xb.run("squash", solvers=[object()], out=tmp_path / "r.h5", set=SCENE)
    with pytest.raises(xb.Error, match="already registered"):
        xb.run("squash", solvers=[Splu(), Splu()], out=tmp_path / "r.h5", set=SCENE)
    with pytest.raises(xb.Error, match="unknown solver 'nope'"):
        xb.run("squash", solvers=["nope"], out=tmp_path / "r.h5", set=SCENE)
    bad = Splu()
    bad.name = "a,b"
    with pytest.raises(xb.Error, match="letters, digits"):
        xb.run("squash", solvers=[bad], out=tmp_path / "r.h5", set=SCENE)
    assert not (tmp_path / "r.h5").exists()
    # A refused call leaves no solver registered: the same name runs afterwards.
    assert xb.run("squash", solvers=[Splu()], out=tmp_path / "r.h5", set=SCENE)[0]["attrs"]["solver"] == "py:splu"


def test_run_appends_to_out_as_documented(tmp_path):
    # A loop over solvers into one file keeps every call's runs (the CLI's run replaces its --out).
    out = tmp_path / "r.h5"
    for s in ("xpbd-gs", "xpbd-jacobi"):
        runs = xb.run("cloth_hang", solvers=[s], out=out, frames=1, set={"resolution": 6})
    assert [r["attrs"]["solver"] for r in runs] == ["xpbd-gs", "xpbd-jacobi"]
    assert [r["name"][:5] for r in runs] == ["0001_", "0002_"]
    assert [r["attrs"]["solver"] for r in xb.read(out)] == ["xpbd-gs", "xpbd-jacobi"]
    # A file that is not a results file is refused before anything runs, and left as it was.
    other = tmp_path / "notes.h5"
    other.write_bytes(b"not hdf5")
    with pytest.raises(xb.Error, match="notes.h5"):
        xb.run("cloth_hang", solvers=["xpbd-gs"], out=other, frames=1, set={"resolution": 6})
    assert other.read_bytes() == b"not hdf5"


def test_solvers_none_is_a_sentence_naming_the_argument(tmp_path):
    with pytest.raises(xb.Error, match="solvers is None"):
        xb.run("squash", solvers=None, out=tmp_path / "r.h5", set=SCENE)
    assert not (tmp_path / "r.h5").exists()
