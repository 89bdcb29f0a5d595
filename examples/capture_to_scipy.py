#!/usr/bin/env python3
"""A captured XPBD linear step in scipy: both forms, what they are built from, and a solve.

capture() runs the scene to (frame, iteration) and returns the system: the dual A Δλ = b, the
primal K Δx = f, and J, the inverse masses, α̃ and the positions. This checks the identities
A = J M⁻¹ Jᵀ + α̃ and K = M + Jᵀ α̃⁻¹ J on the free particles, solves both forms with scipy, and
recovers Δλ from the primal solution.

    python3 examples/capture_to_scipy.py [--scene cloth_hang] [--set resolution=16] [--out PREFIX]
"""
import argparse
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import xpbd_bench as xb


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default="cloth_hang")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="any parameter (default resolution=16 where no mesh or resolution is given)")
    ap.add_argument("--frame", type=int, default=0)
    ap.add_argument("--iteration", type=int, default=0)
    ap.add_argument("--out", help="keep the files: PREFIX.h5, PREFIX_A.mtx, PREFIX_b.mtx, PREFIX_K.mtx, PREFIX_f.mtx")
    args = ap.parse_args()
    sets = dict(kv.split("=", 1) for kv in args.set)
    if "mesh" not in sets:  # a key set where nothing reads it is refused: resolution means nothing for a file mesh
        sets.setdefault("resolution", "16")
    s = xb.capture(args.scene, frame=args.frame, iteration=args.iteration, set=sets, out=args.out)
    print(s, "| scene", s.attrs["scene"], "frame", s.attrs["frame"], "iteration", s.attrs["iteration"])

    # The dual matrix from its parts: M⁻¹ per column of J (each particle's x, y, z).
    minv = sp.diags(np.repeat(s.inv_mass, 3))
    A = (s.J @ minv @ s.J.T + sp.diags(s.alpha_tilde)).tocsr()
    dual_gap = abs(A - s.A).max() / abs(s.A).max()
    print(f"A = J M^-1 J^T + alpha~: max difference {dual_gap:.1e} (relative to max |A|)")

    dlam = sla.spsolve(s.A.tocsc(), s.b)
    print(f"dual:   {s.A.shape[0]} rows, {s.A.nnz} non-zeros, ||b - A dlambda|| / ||b|| = "
          f"{np.linalg.norm(s.b - s.A @ dlam) / np.linalg.norm(s.b):.1e}")
    ok = dual_gap < 1e-12
    if s.K is not None:
        # K over the free particles: pick their columns of J (3 per particle).
        cols = (3 * s.free_particles[:, None] + np.arange(3)).ravel()
        Jf = s.J[:, cols]
        m = np.repeat(1.0 / s.inv_mass[s.free_particles], 3)
        K = (sp.diags(m) + Jf.T @ sp.diags(1.0 / s.alpha_tilde) @ Jf).tocsr()
        primal_gap = abs(K - s.K).max() / abs(s.K).max()
        dx = sla.spsolve(s.K.tocsc(), s.f)
        dlam_p = (s.b - Jf @ dx) / s.alpha_tilde  # Δλ = α̃⁻¹ (b − J Δx)
        print(f"K = M + J^T alpha~^-1 J: max difference {primal_gap:.1e}; primal: {s.K.shape[0]} rows, rigid modes "
              f"{s.rigid_modes.shape}, |dlambda(primal) - dlambda(dual)| / |dlambda| = "
              f"{np.linalg.norm(dlam_p - dlam) / np.linalg.norm(dlam):.1e}")
        ok = ok and primal_gap < 1e-12 and np.linalg.norm(dlam_p - dlam) <= 1e-6 * np.linalg.norm(dlam)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
