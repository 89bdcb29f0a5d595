#!/usr/bin/env python3
"""Bring your own solver: pyamg's smoothed aggregation raced against mgpbd inside the harness.

The solver protocol (docs/python.md): an object with `name`, `setup(A, info)` and `solve(b, tol)`.
Here pyamg builds a smoothed-aggregation hierarchy — in the primal form on K's 3x3 blocks with
the six rigid-body modes the harness hands over as info["near_kernel"] — and preconditions CG.
pyamg cannot refresh a hierarchy's values, so it rebuilds it at every setup (every outer
iteration; a hierarchy kept for the frame stalled the primal squash, whose K changes fast while
the flattened tets re-expand).

    python3 examples/pyamg_solver.py                       # a small squash, both forms
    python3 examples/pyamg_solver.py --set mesh=bunny:12k --out race.h5
"""
import argparse
import os
import sys
import tempfile

import numpy as np
import pyamg

import xpbd_bench as xb


class PyamgSA:
    """pyamg smoothed aggregation (rigid modes in the primal form) as a CG preconditioner."""

    name = "pyamg-sa"

    def __init__(self, maxiter=500):
        self.maxiter = maxiter
        self.ml, self.A = None, None

    def setup(self, A, info):
        self.A = A  # a view of the harness's matrix, valid until the next setup
        # pyamg starts its estimates of λ_max (the smoother's and the prolongator's ω) from NumPy's
        # global random state: seeded here so that a run's numbers repeat (docs/determinism.md).
        np.random.seed(0)
        if info["block_size"] > 1:  # the primal form: nodal aggregation on 3x3 blocks, rigid modes
            bs = info["block_size"]
            self.ml = pyamg.smoothed_aggregation_solver(A.tobsr(blocksize=(bs, bs)), B=info["near_kernel"],
                                                        symmetry="symmetric", max_coarse=100)
        else:
            self.ml = pyamg.smoothed_aggregation_solver(A, symmetry="symmetric", max_coarse=100)

    def solve(self, b, tol):
        residuals = []
        x, _ = pyamg.krylov.cg(self.A, b, tol=tol, maxiter=self.maxiter, M=self.ml.aspreconditioner(),
                               residuals=residuals)
        return x, len(residuals) - 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="squash")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="any parameter (mesh=bunny:12k); the default squash is a ball 6 cells across")
    ap.add_argument("--frames", type=int, default=1)
    ap.add_argument("--form", default="dual,primal")
    ap.add_argument("--out", help="results file (default: a temporary one)")
    ap.add_argument("--progress", action="store_true", help="a live status line on a terminal")
    args = ap.parse_args()
    sets = dict(s.split("=", 1) for s in args.set)
    if "mesh" not in sets:  # a key set where nothing reads it is refused: resolution means nothing for a file mesh
        sets.setdefault("resolution", "6")
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or os.path.join(tmp, "race.h5")
        runs = xb.run(args.scene, solvers=["mgpbd", PyamgSA()], out=out, frames=args.frames, set=sets,
                      form=args.form, progress=args.progress)
    print(f"{'run':40s} {'status':8s} {'outer':>5s} {'linear its':>10s} {'setup s':>8s} {'solve s':>8s} {'wall s':>8s}")
    for r in runs:
        a, d = r["attrs"], r["data"]
        print(f"{r['name']:40s} {a['status']:8s} {a['outer_iterations']:5d} {int(d['linear_iterations'].sum()):10d} "
              f"{d['linear_setup_time'].sum():8.3f} {d['linear_solve_time'].sum():8.3f} {a['wall_time']:8.3f}")
    return 0 if all(r["attrs"]["status"] in ("ok", "max_iterations") for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
