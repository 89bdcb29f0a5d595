#!/usr/bin/env python3
"""Why AMG helps little on a captured XPBD dual system: its Jacobi-scaled spectrum.

usage: python3 scripts/dual_spectrum.py PREFIX [PREFIX ...] [--amg] [-o OUT.png]

PREFIX is what `xpbd-bench capture --out PREFIX` wrote (PREFIX_A.mtx, PREFIX_b.mtx). For each
system it prints the eigenvalues of S = D^-1/2 A D^-1/2 (dense, so at most 12,000 rows): the
extremes, the condition number and how many lie below 1e-4 ... 1e-1 of the largest. Over-determined
constraint sets put a large share of them near the compliance term alpha~ (the self-stresses, the
left null space of J): a near-kernel of that dimension cannot be represented by an aggregation
coarse space that is ten times smaller.

--amg   also PCG iterations to 1e-8 (zero initial guess, pyamg's CG) for plain CG and pyamg's
        aggregation and classical AMGs as preconditioners, each with its operator complexity.
-o      a histogram of the eigenvalues (PNG and PDF).
"""
import argparse
import os
import sys

import numpy as np
import scipy.io as sio

MAX_ROWS = 12000


def load(prefix):
    for suffix in ("_A.mtx", "_b.mtx"):
        if not os.path.exists(prefix + suffix):
            sys.exit(f"dual_spectrum: {prefix + suffix} not found (run xpbd-bench capture --out {prefix})")
    A = sio.mmread(prefix + "_A.mtx").tocsr()
    b = np.asarray(sio.mmread(prefix + "_b.mtx")).ravel()
    return A, b


def scaled_eigenvalues(A):
    if A.shape[0] > MAX_ROWS:
        sys.exit(f"dual_spectrum: {A.shape[0]} rows; the dense eigensolve takes at most {MAX_ROWS}")
    d = 1.0 / np.sqrt(A.diagonal())
    S = A.toarray() * d[:, None] * d[None, :]
    return np.linalg.eigvalsh(S)


def amg_iterations(A, b):
    import pyamg

    def its(M=None):
        res = []
        pyamg.krylov.cg(A, b, x0=np.zeros_like(b), tol=1e-8, maxiter=20000, M=M, residuals=res)
        return len(res) - 1

    cheb = ("chebyshev", {"degree": 3})
    rows = [("cg (no preconditioner)", None, its())]
    for theta in (0.0, 0.25):
        for smooth, label in ((None, "unsmoothed"), ("jacobi", "smoothed")):
            ml = pyamg.smoothed_aggregation_solver(A, strength=("symmetric", {"theta": theta}), smooth=smooth,
                                                   max_coarse=400, presmoother=cheb, postsmoother=cheb)
            rows.append((f"{label} aggregation, theta {theta}", ml.operator_complexity(), its(ml.aspreconditioner())))
    ml = pyamg.rootnode_solver(A, max_coarse=400)
    rows.append(("root-node aggregation", ml.operator_complexity(), its(ml.aspreconditioner())))
    ml, _ = pyamg.aggregation.adaptive_sa_solver(A, num_candidates=6, candidate_iters=5, max_coarse=400)
    rows.append(("adaptive SA, 6 candidates", ml.operator_complexity(), its(ml.aspreconditioner())))
    ml = pyamg.ruge_stuben_solver(A, max_coarse=400)
    rows.append(("classical (Ruge-Stueben)", ml.operator_complexity(), its(ml.aspreconditioner())))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("prefix", nargs="+")
    ap.add_argument("--amg", action="store_true")
    ap.add_argument("-o", "--out")
    args = ap.parse_args()
    spectra = {}
    for prefix in args.prefix:
        A, b = load(prefix)
        w = scaled_eigenvalues(A)
        spectra[os.path.basename(prefix)] = w
        lmax = w[-1]
        print(f"{prefix}: {A.shape[0]} rows, {A.nnz} non-zeros")
        print(f"  eigenvalues of D^-1/2 A D^-1/2: min {w[0]:.3g}, max {lmax:.3g}, condition {lmax / w[0]:.3g}")
        for f in (1e-4, 1e-3, 1e-2, 1e-1):
            k = int((w < f * lmax).sum())
            print(f"  below {f:.0e}·max: {k:6d} ({100.0 * k / len(w):.1f}%)")
        if args.amg:
            rows = amg_iterations(A, b)
            cg = rows[0][2]
            for name, oc, it in rows:
                occ = "" if oc is None else f", operator complexity {oc:.2f}"
                print(f"  PCG iterations to 1e-8, {name}: {it} ({it / cg:.2f} of cg{occ})")
    if args.out:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.4, 4))
        for name, w in spectra.items():
            ax.hist(np.log10(w / w[-1]), bins=80, histtype="step", label=name)
        ax.set_xlabel("log10(eigenvalue / largest) of D^-1/2 A D^-1/2")
        ax.set_ylabel("count")
        ax.legend()
        fig.tight_layout()
        base = os.path.splitext(args.out)[0]
        fig.savefig(base + ".png", dpi=150)
        fig.savefig(base + ".pdf")
        print(f"wrote {base}.png, {base}.pdf")


if __name__ == "__main__":
    main()
