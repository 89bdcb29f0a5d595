#!/usr/bin/env python3
"""Is the primal AMG's trouble on deformed tet-ARAP states a missing near-kernel? A two-level
probe on a captured system (xpbd-bench capture: J, alpha~, inverse masses, positions).

usage: python3 scripts/primal_near_kernel.py SYSTEM.h5 [--eigenvectors 300] [--extra 0,4,8,16]

It rebuilds K = M + J^T alpha~^-1 J from the file, aggregates K's 3x3 node graph (pyamg standard
aggregation, theta 0), and solves K dx = J^T alpha~^-1 b to 1e-8 (relative primal residual, scipy
CG) with a two-level method: degree-3 Chebyshev in D^-1 K on [l/30, 1.1 l] twice before and after,
the smoothed prolongator P = (I - 4/(3l) D^-1 K) T and an exact coarse solve. T per aggregate:
  rigid        the 6 rigid-body modes at the positions (what mgpbd's primal form uses);
  +k exact     the rigid modes plus the k strongest directions, on the aggregate, of the
               lowest --eigenvectors eigenvectors of D^-1 K (weighted by 1/sqrt(eigenvalue)):
               the best local enrichment any adaptive method could find from those modes.
It prints the iterations, the coarse size and the two-level operator complexity for each, and the
spread of the lowest eigenvalues. If exact enrichment needs a coarse space several times larger
to cut the iterations, the low spectrum is too wide for aggregation candidates.
"""
import argparse
import sys

import h5py
import numpy as np
import pyamg
import scipy.sparse as sp
import scipy.sparse.linalg as sla


def load(path):
    with h5py.File(path, "r") as f:
        for name in ("J/data", "alpha_tilde", "inverse_mass", "positions", "b"):
            if name not in f:
                sys.exit(f"primal_near_kernel: {path} has no {name} (capture it with this version of xpbd-bench)")
        w = f["inverse_mass"][:]
        if (w <= 0).any():
            sys.exit("primal_near_kernel: pinned particles (inverse mass 0) are not handled by this probe")
        n = 3 * len(w)
        J = sp.csr_matrix((f["J/data"][:], f["J/indices"][:], f["J/indptr"][:]), shape=(len(f["alpha_tilde"]), n))
        return J, f["alpha_tilde"][:], w, f["positions"][:].reshape(-1, 3), f["b"][:]


def rigid_modes(x):
    c = x - x.mean(axis=0)
    B = np.zeros((3 * len(x), 6))
    for k in range(3):
        B[k::3, k] = 1
    B[0::3, 3], B[1::3, 3] = -c[:, 1], c[:, 0]
    B[1::3, 4], B[2::3, 4] = -c[:, 2], c[:, 1]
    B[0::3, 5], B[2::3, 5] = c[:, 2], -c[:, 0]
    return B


def chebyshev(K, dinv, lam, b, x, degree=3):
    hi, lo = 1.1 * lam, lam / 30
    theta, delta = (hi + lo) / 2, (hi - lo) / 2
    sigma = theta / delta
    rho = 1 / sigma
    d = dinv * (b - K @ x) / theta
    for k in range(1, degree + 1):
        x = x + d
        if k == degree:
            return x
        rho_new = 1 / (2 * sigma - rho)
        d = rho_new * rho * d + 2 * rho_new / delta * dinv * (b - K @ x)
        rho = rho_new


def two_level(K, rhs, T, lam):
    dinv = 1 / K.diagonal()
    P = (T - (4 / (3 * lam)) * sp.diags(dinv) @ (K @ T)).tocsr()
    Kc = (P.T @ K @ P).tocsc()
    coarse = sla.splu(Kc)

    def vcycle(r):
        x = np.zeros_like(r)
        for _ in range(2):
            x = chebyshev(K, dinv, lam, r, x)
        x = x + P @ coarse.solve(P.T @ (r - K @ x))
        for _ in range(2):
            x = chebyshev(K, dinv, lam, r, x)
        return x

    its = [0]
    M = sla.LinearOperator(K.shape, vcycle)
    _, info = sla.cg(K, rhs, rtol=1e-8, maxiter=2000, M=M, callback=lambda _: its.__setitem__(0, its[0] + 1))
    return its[0] if info == 0 else f">{its[0]}", Kc.shape[0], (K.nnz + Kc.nnz) / K.nnz


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("system")
    ap.add_argument("--eigenvectors", type=int, default=300)
    ap.add_argument("--extra", default="0,4,8,16", help="enrichment columns per aggregate to try")
    a = ap.parse_args()
    J, alpha, w, x, b = load(a.system)
    K = (sp.diags(np.repeat(1 / w, 3)) + J.T @ sp.diags(1 / alpha) @ J).tocsr()
    rhs = J.T @ (b / alpha)
    d = K.diagonal()
    Kb = K.tobsr(blocksize=(3, 3))
    N = sp.csr_matrix((np.sqrt((Kb.data ** 2).sum(axis=(1, 2))), Kb.indices, Kb.indptr))
    agg = pyamg.aggregation.standard_aggregation(pyamg.strength.symmetric_strength_of_connection(N, 0.0))[0]
    agg = agg.tocsr().indices
    members = [np.flatnonzero(agg == a_) for a_ in range(agg.max() + 1)]
    Dh = sp.diags(1 / np.sqrt(d))
    S = (Dh @ K @ Dh).tocsc()
    lam = sla.eigsh(S, k=1, which="LA", return_eigenvectors=False)[0]
    vals, W = sla.eigsh(S, k=min(a.eigenvectors, K.shape[0] - 2), sigma=0, which="LM")
    V = (Dh @ W) / np.sqrt(vals)
    print(f"{a.system}: {K.shape[0]} rows, {len(members)} aggregates; lambda_max(D^-1 K) {lam:.3g}; "
          f"lowest {len(vals)} eigenvalues {vals.min():.2e} .. {vals.max():.2e}")
    print("| candidates | coarse rows | operator complexity | iterations |\n|---|---|---|---|")
    for extra in (int(e) for e in a.extra.split(",")):
        rows, cols, data, col = [], [], [], 0
        for nodes in members:
            dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
            Q, _ = np.linalg.qr(rigid_modes(x[nodes]))
            if extra:
                E = V[dofs] - Q @ (Q.T @ V[dofs])
                U, s, _ = np.linalg.svd(E, full_matrices=False)
                Q = np.hstack([Q, U[:, :min(extra, int((s > 1e-3 * s[0]).sum()))]])
            r, c = np.meshgrid(dofs, col + np.arange(Q.shape[1]), indexing="ij")
            rows.append(r.ravel()), cols.append(c.ravel()), data.append(Q.ravel())
            col += Q.shape[1]
        T = sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(K.shape[0], col))
        its, nc, oc = two_level(K, rhs, T, lam)
        label = "rigid" if extra == 0 else f"rigid + {extra} exact"
        print(f"| {label} | {nc} | {oc:.2f} | {its} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
