#!/usr/bin/env python3
"""Independent check of the in-house AMG: mgpbd against pyamg on the same matrices.

For captured dual systems (cloth_hang, bar_hang) and several strength thresholds θ_s, compare
  harness:  xpbd-bench solve --solver mgpbd with amg.near_kernel=ones, amg.aggregation=standard,
            amg.strength_threshold=θ, amg.smoother=jacobi (1 sweep), amg.max_coarse, amg.max_levels
  pyamg:    smoothed_aggregation_solver(A, B=None, strength=('symmetric', {'theta': θ}),
            aggregate='standard', smooth=None, improve_candidates=None,
            presmoother=postsmoother=('jacobi', {'omega': 1.0, 'withrho': True, 'iterations': 1}),
            max_coarse=<same>, max_levels=<same>), then ml.solve(b, tol, accel='cg').
What is compared, and why it is comparable:
  - number of levels: must be equal (same strength rule |A_ij| >= θ sqrt(|A_ii A_jj|), same
    greedy standard aggregation, same stopping rule rows <= max_coarse or max_levels);
  - operator complexity Σnnz(A_l)/nnz(A_0): within 5%;
  - PCG iterations to ‖r‖ <= tol‖b‖ from x = 0 with one V-cycle as preconditioner: within 20%.
    Both smoothers are weighted Jacobi with ω = 1/λ_max(D⁻¹A) (pyamg's withrho divides ω = 1 by
    its estimate of ρ(D⁻¹A)), one pre- and one post-sweep, and a direct solve on the coarsest level
    (pyamg's default 'pinv', mgpbd's Cholesky). improve_candidates=None keeps pyamg's B = 1
    (its default would smooth B before building P, which the harness's `ones` does not).
The authors' Python AMG (the V-cycle of their near-kernel table; scripts/authors_checks.py
near_kernel --vcycle python) on the `enlarge` start of the squash ball: mgpbd with
amg.smoother_sweeps=10, amg.jacobi_omega=level0, amg.coarse_solver=direct against pyamg with
('jacobi', {'omega': 1/ρ(D⁻¹A₀), 'withrho': False, 'iterations': 10}) on every level, θ = 0, B = 1,
unsmoothed P: PCG iterations to 1e-6 within 10% (with one sweep instead of ten both need ~4x more).
Exit codes: 0 all checks pass, 1 a check failed, 77 skipped (mgpbd is not registered).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import pyamg
import scipy.sparse as sp
from pyamg.relaxation.smoothing import rho_D_inv_A


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit(f"pyamg_check: command failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    return p.stdout


def load_system(path):
    with h5py.File(path, "r") as f:
        n = int(f.attrs["rows"])
        A = sp.csr_matrix((f["A/data"][:], f["A/indices"][:], f["A/indptr"][:]), shape=(n, n))
        b = f["b"][:]
    return A, b


def harness_mgpbd(binary, system, theta, opts, workdir, extra=None, tol=None):
    out = os.path.join(workdir, f"mgpbd_{os.path.basename(system)}_{theta}.h5")
    sets = {
        "amg.near_kernel": "ones",
        "amg.aggregation": "standard",
        "amg.strength_threshold": theta,
        "amg.smoother": "jacobi",
        "amg.smoother_sweeps": 1,
        "amg.max_coarse": opts.max_coarse,
        "amg.max_levels": opts.max_levels,
        **(extra or {}),
    }
    cmd = [binary, "solve", "--system", system, "--solver", "mgpbd", "--tol", str(tol or opts.tol), "--set", "form=dual", "--out", out]
    for k, v in sets.items():
        cmd += ["--set", f"{k}={v}"]
    run(cmd)
    rep = json.loads(run([binary, "report", out, "--format", "json"]))
    assert len(rep) == 1, rep
    r = rep[0]
    with h5py.File(out, "r") as f:
        g = f["runs"][r["run"]]
        rows = list(g["level_rows"][:]) if "level_rows" in g else []
    return {"status": r["status"], "levels": int(r["levels"]), "oc": float(r["operator_complexity"]),
            "iterations": int(r["iterations"]), "residual": float(r["final_relative_residual"]),
            "rows": [int(x) for x in rows]}


def pyamg_sa(A, b, theta, opts):
    jac = ("jacobi", {"omega": 1.0, "withrho": True, "iterations": 1})
    ml = pyamg.smoothed_aggregation_solver(
        A, B=None, symmetry="symmetric", strength=("symmetric", {"theta": theta}), aggregate="standard",
        smooth=None, improve_candidates=None, presmoother=jac, postsmoother=jac,
        max_coarse=opts.max_coarse, max_levels=opts.max_levels)
    res = []
    x = ml.solve(b, x0=np.zeros_like(b), tol=opts.tol, accel="cg", maxiter=1000, residuals=res)
    rel = np.linalg.norm(b - A @ x) / np.linalg.norm(b)
    return {"levels": len(ml.levels), "oc": ml.operator_complexity(), "iterations": len(res) - 1,
            "residual": rel, "rows": [lvl.A.shape[0] for lvl in ml.levels]}


def authors_python_vcycle(opts, workdir):
    """The authors' Python AMG V-cycle: mgpbd's keys against pyamg with ω of level 0 on every level."""
    prefix = os.path.join(workdir, "squash_enlarge")
    run([opts.binary, "capture", "--scene", "squash", "--set", "init=enlarge", "--set", "resolution=12",
         "--frame", "0", "--iteration", "0", "--out", prefix])
    A, b = load_system(prefix + ".h5")
    tol = 1e-6
    extra = {"amg.smoother_sweeps": 10, "amg.jacobi_omega": "level0", "amg.coarse_solver": "direct"}
    h = harness_mgpbd(opts.binary, prefix + ".h5", 0.0, opts, workdir, extra, tol)
    jac = ("jacobi", {"omega": 1.0 / rho_D_inv_A(A), "withrho": False, "iterations": 10})
    ml = pyamg.smoothed_aggregation_solver(
        A, B=None, symmetry="symmetric", strength=("symmetric", {"theta": 0.0}), smooth=None,
        improve_candidates=None, presmoother=jac, postsmoother=jac, max_coarse=opts.max_coarse)
    res = []
    ml.solve(b, x0=np.zeros_like(b), tol=tol, accel="cg", maxiter=1000, residuals=res)
    p_its = len(res) - 1
    print(f"authors' Python V-cycle (squash enlarge, Jacobi x10, level-0 omega): PCG iterations "
          f"{h['iterations']} (mgpbd) / {p_its} (pyamg); rows {h['rows']} / {[l.A.shape[0] for l in ml.levels]}")
    if h["status"] != "ok" or abs(h["iterations"] - p_its) > 0.1 * p_its:
        return [f"authors' Python V-cycle: PCG iterations {h['iterations']} (mgpbd, {h['status']}) vs {p_its} (pyamg)"]
    return []


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True, help="path to xpbd-bench")
    ap.add_argument("--thetas", default="0,0.1,0.25")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--max-coarse", type=int, default=400)
    ap.add_argument("--max-levels", type=int, default=10)
    ap.add_argument("--workdir", help="keep the captured systems and results here (default: a temp dir)")
    opts = ap.parse_args()
    # pyamg starts its estimates of ρ(D⁻¹A) from NumPy's global random state: seeded, so that its
    # iteration counts repeat from one run to the next (docs/determinism.md).
    np.random.seed(0)

    listing = run([opts.binary, "list"])
    if not any(line.split()[:1] == ["mgpbd"] for line in listing.splitlines()):
        print("pyamg_check: SKIPPED: mgpbd is not registered in this build")
        return 77

    workdir = opts.workdir or tempfile.mkdtemp(prefix="xb_pyamg_")
    os.makedirs(workdir, exist_ok=True)
    # Deformed states (a few frames in), large enough for more than one level with max_coarse 400.
    cases = [
        ("cloth_hang", ["resolution=32"], 2, 0),
        ("bar_hang", ["resolution=4", "aspect=5"], 0, 1),
    ]
    thetas = [float(t) for t in opts.thetas.split(",")]
    failures = []
    print(f"pyamg {pyamg.__version__}; tol {opts.tol}, max_coarse {opts.max_coarse}, max_levels {opts.max_levels}")
    print(f"{'system':<12} {'theta':>5} | {'levels':>9} | {'operator complexity':>21} | {'PCG iterations':>15} | rows per level (mgpbd / pyamg)")
    for scene, sets, frame, iteration in cases:
        prefix = os.path.join(workdir, scene)
        cmd = [opts.binary, "capture", "--scene", scene, "--frame", str(frame), "--iteration", str(iteration), "--out", prefix]
        for s in sets:
            cmd += ["--set", s]
        run(cmd)
        A, b = load_system(prefix + ".h5")
        for theta in thetas:
            h = harness_mgpbd(opts.binary, prefix + ".h5", theta, opts, workdir)
            p = pyamg_sa(A, b, theta, opts)
            print(f"{scene:<12} {theta:>5} | {h['levels']:>4} {p['levels']:>4} | {h['oc']:>10.4f} {p['oc']:>10.4f} | "
                  f"{h['iterations']:>7} {p['iterations']:>7} | {h['rows']} / {p['rows']}")
            tag = f"{scene} theta={theta}"
            if h["status"] != "ok":
                failures.append(f"{tag}: mgpbd status {h['status']}")
            if p["residual"] > 10 * opts.tol:
                failures.append(f"{tag}: pyamg did not converge (relative residual {p['residual']:.3g})")
            if h["levels"] != p["levels"]:
                failures.append(f"{tag}: levels {h['levels']} (mgpbd) != {p['levels']} (pyamg)")
            if abs(h["oc"] - p["oc"]) > 0.05 * p["oc"]:
                failures.append(f"{tag}: operator complexity {h['oc']:.4f} (mgpbd) vs {p['oc']:.4f} (pyamg): more than 5% apart")
            if abs(h["iterations"] - p["iterations"]) > 0.2 * p["iterations"]:
                failures.append(f"{tag}: PCG iterations {h['iterations']} (mgpbd) vs {p['iterations']} (pyamg): more than 20% apart")
    failures += authors_python_vcycle(opts, workdir)
    for f in failures:
        print("FAIL:", f)
    print("pyamg_check:", "FAILED" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
