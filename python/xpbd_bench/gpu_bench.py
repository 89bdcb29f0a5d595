"""The device benchmark of mgpbd's solve phase (docs/gpu.md), needing only NumPy/SciPy, h5py and
CuPy (not the C++ build):

    python3 -m xpbd_bench.gpu_bench CAPTURE.h5... --out RESULT.json [--tol 1e-8 0.1]

Each capture must hold an exported hierarchy (xpbd_bench.export_hierarchy: /hierarchy/<form>).
Per system (capture, form): the transfer of the levels to the device, a values refresh (new
values into the levels' arrays, and R A P per level on the device), one V-cycle, and PCG to each
tolerance (iterations, time per iteration and per solve, the relative residual; the primal form
stops on the dual residual, as mgpbd does with linear.stop_norm = dual); the bytes a V-cycle moves
against the measured device-to-device copy bandwidth; and, per capture, CG with a Jacobi
preconditioner on the dual system (cupyx's, or scipy's on NumPy) as the baseline. Without a
device it runs on NumPy, its timings marked as CPU ones (backend "numpy"); --backend cupy makes a
missing CuPy or device an error instead. Each solve also reports the kernel launches and blocking
host reads it made (counted by the backend's operations, gpu_kernels.py: the same count on NumPy).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import scipy.sparse

from . import hierarchy_io
from .gpu import Backend, DeviceHierarchy, pcg
from .gpu_kernels import Csr

LOOSE_TOL = 0.1  # the race's loosest inner tolerance: linear.forcing_max (docs/race.md)


def timed(be, fn, repeat=1):
    """(best seconds over `repeat` calls, the last result), the device synchronised around each."""
    best, out = math.inf, None
    for _ in range(repeat):
        be.synchronize()
        t = time.perf_counter()
        out = fn()
        be.synchronize()
        best = min(best, time.perf_counter() - t)
    return best, out


def copy_bandwidth(be, mib=256):
    """Bytes per second of a device-to-device copy (read + write counted), best of 5."""
    n = (mib << 20) // 4
    src = be.xp.ones(n, dtype=np.float32)
    dst = be.xp.empty_like(src)
    t, _ = timed(be, lambda: dst.__setitem__(slice(None), src), repeat=5)
    return 2 * 4 * n / t


def csr_bytes(m, value_bytes):
    return m.nnz * (value_bytes + 4) + (m.shape[0] + 1) * 4


def vcycle_bytes(dh):
    """What one V-cycle reads and writes at least: every matrix pass once (A_l's values and
    indices, R, P, the (block) inverse diagonals) and its vectors (x, b, the result per pass); the
    coarse solve's dense inverse in double. A model, not a measurement."""
    vb = np.dtype(dh.dtype).itemsize
    total = 0
    for L in dh.levels:
        n = L.A.shape[0]
        passes = L.sweeps * len(L.steps)
        dinv = L.S.block_inv.size * vb + L.S.nodes * 12  # blocks, node starts and offsets
        total += (2 * passes) * (csr_bytes(L.A, vb) + dinv + 4 * n * vb)
        total += csr_bytes(L.R, vb) + csr_bytes(L.P, vb) + 4 * n * vb
    if dh.coarse_inv is not None:
        total += dh.coarse_inv.size * 8
    return int(total)


def refresh(be, dh, export):
    """New values on the same pattern: each level's A values copied into its device arrays (as a
    refresh each outer iteration would upload them), and A_{l+1} = R_l A_l P_l on the device in
    double; returns (upload s, Galerkin s, max relative difference of the products to the export)."""
    levels = export["levels"]

    def upload():
        for L, E in zip(dh.levels, levels):
            L.A.data[...] = be.array(scipy.sparse.csr_matrix(E["A"]).data, dh.dtype)
    t_up, _ = timed(be, upload)
    As = [be.csr(E["A"], np.float64) for E in levels]
    Ps = [be.csr(E["P"], np.float64) for E in levels[:-1]]
    Rs = [be.csr(E["R"], np.float64) for E in levels[:-1]]
    t_rap, products = timed(be, lambda: [Rs[l] @ As[l] @ Ps[l] for l in range(len(Ps))])
    diff = 0.0
    for l, C in enumerate(products):
        C = C.get() if be.device else C
        ref = scipy.sparse.csr_matrix(levels[l + 1]["A"])
        diff = max(diff, abs(C - ref).max() / abs(ref).max())
    return t_up, t_rap, diff


def solve_system(be, path, form, tols, repeat, maxit):
    export, data = hierarchy_io.read(path, form)
    t_transfer, dh = timed(be, lambda: (DeviceHierarchy(export, be), Csr(be.xp, data["matrix"], np.float64)))
    dh, A = dh
    b = be.array(data["rhs"], np.float64)
    G, dual_norm = None, 1.0
    if "dual_map" in data:  # the primal form stops on the dual residual −J M⁻¹ r_K
        G = Csr(be.xp, data["dual_map"], np.float64)
        dual_norm = float(np.linalg.norm(data["dual_rhs"]))
    t_up, t_rap, rap_diff = refresh(be, dh, export)
    t_vc, _ = timed(be, lambda: dh.vcycle(b), repeat=max(repeat, 3))
    ops = be.ops
    ops.reset_counts()
    dh.vcycle(b)
    vcycle_launches = ops.launches
    out = {"capture": os.path.basename(path), "form": form, "rows": dh.rows[0], "nnz": dh.nnz[0],
           "level_rows": dh.rows, "level_nnz": dh.nnz, "precision": dh.precision,
           "transfer_seconds": t_transfer, "refresh_upload_seconds": t_up, "refresh_galerkin_seconds": t_rap,
           "refresh_galerkin_max_rel_diff": rap_diff, "vcycle_seconds": t_vc, "vcycle_bytes": vcycle_bytes(dh), "vcycle_launches": vcycle_launches,
           "solves": []}
    for tol in tols:
        ops.reset_counts()
        t, (x, its, status) = timed(be, lambda: pcg(A, b, dh.vcycle, tol, maxit, ops, dual_map=G, dual_scale=dual_norm),
                                    repeat=repeat)
        launches, syncs = ops.launches / repeat, ops.syncs / repeat
        r = ops.residual(A, x, b, be.xp.empty_like(b))
        res = float(be.xp.linalg.norm(r)) / float(be.xp.linalg.norm(b))
        dual = float(be.xp.linalg.norm(ops.spmv(G, r, be.xp.empty(G.shape[0])))) / dual_norm if G is not None else res
        out["solves"].append({"tol": tol, "status": status, "iterations": its, "solve_seconds": t,
                              "seconds_per_iteration": t / its if its else None, "relative_residual": res,
                              "dual_relative_residual": dual, "launches": launches, "host_syncs": syncs,
                              "launches_per_iteration": launches / its if its else None})
    return out


def jacobi_cg(be, path, tols, maxit):
    """CG with a Jacobi preconditioner on the capture's dual system: cupyx's cg on a device,
    scipy's on NumPy, to ‖r‖ ≤ tol·‖b‖."""
    import h5py
    with h5py.File(path, "r") as f:
        A = hierarchy_io.dual_matrix(f)
        b_host = f["b"][()]
    if be.device:
        import cupyx.scipy.sparse.linalg as spla
    else:
        import scipy.sparse.linalg as spla
    Ad, b = be.csr(A, np.float64), be.array(b_host, np.float64)
    dinv = 1.0 / be.array(A.diagonal(), np.float64)
    M = spla.LinearOperator(A.shape, matvec=lambda r: dinv * r, dtype=np.float64)
    rows = []
    for tol in tols:
        count = [0]

        def cb(_):
            count[0] += 1
        try:
            call = lambda: spla.cg(Ad, b, rtol=tol, atol=0.0, maxiter=maxit, M=M, callback=cb)  # noqa: E731
            t, (x, info) = timed(be, call)
        except TypeError:  # an older signature: tol instead of rtol
            count[0] = 0
            call = lambda: spla.cg(Ad, b, tol=tol, atol=0.0, maxiter=maxit, M=M, callback=cb)  # noqa: E731
            t, (x, info) = timed(be, call)
        res = float(be.xp.linalg.norm(b - Ad @ x)) / float(be.xp.linalg.norm(b))
        rows.append({"tol": tol, "iterations": count[0], "solve_seconds": t, "relative_residual": res,
                     "converged": info == 0, "seconds_per_iteration": t / count[0] if count[0] else None})
    return {"capture": os.path.basename(path), "form": "dual", "rows": A.shape[0], "nnz": A.nnz, "solves": rows}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m xpbd_bench.gpu_bench", description=__doc__.split("\n\n")[0])
    ap.add_argument("captures", nargs="+", help="PREFIX.h5 files with an exported hierarchy")
    ap.add_argument("--out", required=True, help="the JSON file to write")
    ap.add_argument("--tol", type=float, nargs="+", default=[1e-8, LOOSE_TOL],
                    help="PCG tolerances (default: 1e-8 and the race's loose 0.1)")
    ap.add_argument("--backend", default="auto", choices=["auto", "cupy", "numpy"])
    ap.add_argument("--repeat", type=int, default=3, help="timed repetitions (the best is kept)")
    ap.add_argument("--max-iterations", type=int, default=1000)
    ap.add_argument("--baseline-max-iterations", type=int, default=20000, help="CG with Jacobi's cap")
    ap.add_argument("--no-baseline", action="store_true", help="skip CG with Jacobi")
    a = ap.parse_args(argv)
    try:
        be = Backend(a.backend)
    except RuntimeError as e:  # --backend cupy without CuPy or a device: an error, never a NumPy run
        print(f"gpu_bench: {e}", file=sys.stderr)
        return 2
    for p in a.captures:
        if not os.path.exists(p) or not hierarchy_io.forms(p):
            ap.error(f"{p}: no such file, or no exported hierarchy in it (xpbd_bench.export_hierarchy)")
    result = {"backend": be.name, "device": be.reason, "timings": "device" if be.device else "cpu (NumPy/SciPy)",
              "copy_bandwidth_bytes_per_second": copy_bandwidth(be, 256 if be.device else 32),
              "systems": [], "jacobi_cg": []}
    bw = result["copy_bandwidth_bytes_per_second"]
    for p in a.captures:
        for form in hierarchy_io.forms(p):
            s = solve_system(be, p, form, a.tol, a.repeat, a.max_iterations)
            s["vcycle_fraction_of_copy_bandwidth"] = s["vcycle_bytes"] / s["vcycle_seconds"] / bw
            result["systems"].append(s)
            print(f"{s['capture']} {form}: {s['rows']} rows, V-cycle {1e3 * s['vcycle_seconds']:.2f} ms "
                  f"({100 * s['vcycle_fraction_of_copy_bandwidth']:.0f}% of copy bandwidth); "
                  + "; ".join(f"tol {x['tol']:g}: {x['iterations']} its, {1e3 * x['solve_seconds']:.1f} ms"
                              for x in s["solves"]), file=sys.stderr)
        if not a.no_baseline:
            result["jacobi_cg"].append(jacobi_cg(be, p, a.tol, a.baseline_max_iterations))
    with open(a.out, "w") as f:
        json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
