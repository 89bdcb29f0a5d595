"""mgpbd's solve phase on a GPU (docs/gpu.md): the hierarchy the C++ setup builds
(xpbd_bench.amg_hierarchy: solvers/amg/hierarchy_export.hpp), its V-cycle in float (as
amg.precision = single) and PCG in double on the device through CuPy, or on NumPy/SciPy where
CuPy or a device is absent (what CI tests). One code path: `Backend` is the array-module switch.

    from xpbd_bench.gpu import MgpbdGpu
    xb.run("squash", solvers=["mgpbd", MgpbdGpu()], out="r.h5")     # races as py:mgpbd-gpu

The V-cycle, smoothers, coarse solve and PCG loop follow solvers/amg/vcycle.cpp and
solvers/krylov/pcg.cpp step for step. This module needs only NumPy/SciPy (and CuPy for a
device): the C++ module is imported only by MgpbdGpu.setup, so gpu_bench runs without the build.
"""
import math
import os

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg


class Backend:
    """The array module: CuPy (+ cupyx.scipy.sparse) on a device, else NumPy (+ scipy.sparse)."""

    def __init__(self, kind="auto"):
        kind = os.environ.get("XB_GPU_BACKEND", kind) if kind == "auto" else kind
        if kind not in ("auto", "cupy", "numpy"):
            raise ValueError(f"backend '{kind}': use auto, cupy or numpy")
        self.xp, self.sparse, self.reason = np, scipy.sparse, "numpy requested"
        if kind != "numpy":
            found, why = device_module()
            if found is not None:
                self.xp, self.sparse = found
            elif kind == "cupy":
                raise RuntimeError(f"backend cupy: {why}")
            self.reason = why
        self.device = self.xp is not np
        self.name = "cupy" if self.device else "numpy"

    def synchronize(self):
        if self.device:
            self.xp.cuda.get_current_stream().synchronize()

    def array(self, a, dtype=None):
        return self.xp.asarray(np.asarray(a), dtype=dtype)

    def host(self, a):
        return a.get() if self.device else np.asarray(a)

    def csr(self, m, dtype):
        """A scipy CSR matrix on the backend, its values in dtype (int32 indices)."""
        m = scipy.sparse.csr_matrix(m)
        if not self.device:
            return scipy.sparse.csr_matrix((m.data.astype(dtype), m.indices.astype(np.int32),
                                            m.indptr.astype(np.int32)), shape=m.shape)
        return self.sparse.csr_matrix((self.array(m.data, dtype), self.array(m.indices, np.int32),
                                       self.array(m.indptr, np.int32)), shape=m.shape)


def device_module():
    """((cupy, cupyx.scipy.sparse), "found: <device>") or (None, why not)."""
    try:
        import cupy
        import cupyx.scipy.sparse
    except Exception as e:  # ImportError, or a CUDA library that does not load
        return None, f"no CuPy ({type(e).__name__}: {e})"
    try:
        n = cupy.cuda.runtime.getDeviceCount()
        if n < 1:
            return None, "CuPy found no CUDA device"
        name = cupy.cuda.runtime.getDeviceProperties(0)["name"]
        name = name.decode() if isinstance(name, bytes) else str(name)
    except Exception as e:
        return None, f"CuPy found no usable device ({type(e).__name__}: {e})"
    return (cupy, cupyx.scipy.sparse), f"found: {name}"


def device_info():
    """What xb.solvers() reports for py:mgpbd-gpu: (device found?, the sentence why)."""
    found, why = device_module()
    return found is not None, why


def block_diagonal(node_start, block_inv, n):
    """The node blocks D_I⁻¹ (row-major, node after node) as one block-diagonal CSR matrix."""
    start = np.asarray(node_start, dtype=np.int64)
    sizes = np.diff(start)
    node_of_row = np.repeat(np.arange(len(sizes)), sizes)
    row_len = sizes[node_of_row]
    indptr = np.concatenate([[0], np.cumsum(row_len)])
    first = np.repeat(start[node_of_row], row_len)
    within = np.arange(indptr[-1]) - np.repeat(indptr[:-1], row_len)
    return scipy.sparse.csr_matrix((np.asarray(block_inv), first + within, indptr), shape=(n, n))


class _Level:
    """A level on the backend: A (and P, R to the next level) in the V-cycle's dtype, its smoother."""

    def __init__(self, be, level, dtype):
        self.A = be.csr(level["A"], dtype)
        self.P = be.csr(level["P"], dtype) if level.get("P") is not None else None
        self.R = be.csr(level["R"], dtype) if level.get("R") is not None else None
        s = level.get("smoother")
        self.steps, self.sweeps, self.Dinv, self.dinv = [], 0, None, None
        if s is None:
            return
        if not s["polynomial"]:
            raise ValueError(f"mgpbd-gpu runs the polynomial smoothers (jacobi, chebyshev, block_jacobi, "
                             f"block_chebyshev), not amg.smoother={s['kind']}")
        self.steps = [(float(c1), float(c2)) for c1, c2 in np.asarray(s["steps"]).reshape(-1, 2)]
        self.sweeps = int(s["sweeps"])
        if s.get("node_start") is None:
            self.dinv = be.array(s["inv_diag"], dtype)
        else:
            self.Dinv = be.csr(block_diagonal(s["node_start"], s["block_inv"], self.A.shape[0]), dtype)

    def apply_dinv(self, r):
        return self.dinv * r if self.Dinv is None else self.Dinv @ r

    def smooth(self, b, x):
        """`sweeps` sweeps of the steps: d = c1·d + c2·D⁻¹(b − A x), x += d (x None: from zero)."""
        d = None
        for _ in range(self.sweeps):
            for c1, c2 in self.steps:
                if x is None:  # from zero: d = c2·D⁻¹b, no product with A
                    d = c2 * self.apply_dinv(b)
                    x = d.copy()
                    continue
                t = self.apply_dinv(b - self.A @ x)
                d = c2 * t if c1 == 0 else c1 * d + c2 * t
                x += d
        return x


class DeviceHierarchy:
    """The exported levels (a dict: AmgHierarchy.export() or gpu_bench's read from a capture) on
    the backend; vcycle(b) is Hierarchy::vcycle."""

    def __init__(self, export, backend):
        self.be = be = backend
        self.precision = export["precision"]
        self.dtype = np.float32 if self.precision == "single" else np.float64
        self.coarse_solver = export["coarse_solver"]
        levels = export["levels"]
        self.levels = [_Level(be, L, self.dtype) for L in levels[:-1]]
        self.rows = [int(L["A"].shape[0]) for L in levels]
        self.nnz = [int(L["A"].nnz) for L in levels]
        self._set_coarse(levels[-1])

    def _set_coarse(self, level):
        """The coarsest solve in double: its smoother from zero, or Cholesky (dense while small,
        as the C++ does up to 1500 rows: applied as the explicit inverse, one product on the device)."""
        self.coarse_lu = self.coarse_inv = self.coarse_level = None
        if self.coarse_solver == "smoother":
            self.coarse_level = _Level(self.be, level, np.float64)
            return
        Ac = scipy.sparse.csr_matrix(level["A"]).toarray()
        if Ac.shape[0] <= 1500:
            factor = scipy.linalg.cho_factor(Ac, lower=True)
            self.coarse_inv = self.be.array(scipy.linalg.cho_solve(factor, np.eye(Ac.shape[0])), np.float64)
        else:  # max_levels stopped the coarsening early: a sparse LU on the host
            self.coarse_lu = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(level["A"]))

    def coarse(self, b):
        if self.coarse_level is not None:
            return self.coarse_level.smooth(b, None)
        if self.coarse_inv is not None:
            return self.coarse_inv @ b
        return self.be.array(self.coarse_lu.solve(self.be.host(b)), np.float64)

    def vcycle(self, b):
        """One V-cycle from x = 0 (Algorithm 2) of a double vector b; returns x in double."""
        xp = self.be.xp
        if not self.levels:
            return self.coarse(b)
        scale = 1.0
        if self.dtype == np.float32:
            # vcycle.cpp: the float V-cycle runs on b/‖b‖∞ and scales back.
            scale = float(xp.max(xp.abs(b)))
            if not (scale > 0) or not math.isfinite(scale):
                return xp.zeros_like(b) if scale == 0 else xp.full_like(b, scale)
        rhs, sol = [(b / scale).astype(self.dtype)], []
        for L in self.levels:
            x = L.smooth(rhs[-1], None)
            sol.append(x)
            rhs.append(L.R @ (rhs[-1] - L.A @ x))
        xc = self.coarse(rhs[-1].astype(np.float64)).astype(self.dtype)
        for l in range(len(self.levels) - 1, -1, -1):
            L = self.levels[l]
            sol[l] += L.P @ xc
            xc = L.smooth(rhs[l], sol[l])
        return scale * xc.astype(np.float64)


def pcg(A, b, precond, tol, max_iterations, xp, rel=None, natural_norm=False):
    """solvers/krylov/pcg.cpp's loop: from x = 0 to ‖r‖₂ ≤ tol·‖b‖₂ (rel(r): the relative residual
    measured instead, e.g. the dual one of a primal residual; natural_norm: √(rᵀM⁻¹r) ≤ tol·√(r₀ᵀM⁻¹r₀)).
    Returns (x, iterations, status)."""
    x = xp.zeros_like(b)
    r = b.copy()
    bnorm = float(xp.linalg.norm(b))
    if not math.isfinite(bnorm):
        return x, 0, "breakdown"
    if bnorm == 0:
        return x, 0, "converged"
    z = precond(r)
    p = z.copy()
    rz = float(xp.dot(r, z))
    rz0, status, its = rz, "max_iterations", 0
    for k in range(max_iterations):
        Ap = A @ p
        pAp = float(xp.dot(p, Ap))
        if not (pAp > 0) or not math.isfinite(pAp) or not (rz > 0):
            status = "breakdown"
            break
        alpha = rz / pAp
        x += alpha * p
        r -= alpha * Ap
        its = k + 1
        rnorm = rel(r) * bnorm if rel is not None else math.sqrt(float(xp.dot(r, r)))
        if not math.isfinite(rnorm):
            status = "breakdown"
            break
        if not natural_norm and rnorm <= tol * bnorm:
            status = "converged"
            break
        z = precond(r)
        rz_new = float(xp.dot(r, z))
        if natural_norm and rz_new >= 0 and math.sqrt(rz_new) <= tol * math.sqrt(rz0):
            status = "converged"
            break
        beta = rz_new / rz
        rz = rz_new
        p = z + beta * p
    return x, its, status


def _settings(kwargs):
    """MgpbdGpu's keyword arguments as amg.* keys (amg. may be left off) and seed."""
    out = {}
    for k, v in kwargs.items():
        key = k if k.startswith("amg.") or k == "seed" else "amg." + k
        out[key] = ("true" if v else "false") if isinstance(v, bool) else repr(v) if isinstance(v, float) else str(v)
    return out


class MgpbdGpu:
    """mgpbd with its solve phase on the backend: a solver of the Python protocol (docs/python.md)
    that runs as py:mgpbd-gpu. Keyword arguments: amg.* settings (MgpbdGpu(**{"amg.smoother":
    "jacobi"}) or smoother="jacobi"), seed, and max_iterations (linear.max_iterations' default);
    backend: auto | cupy | numpy. The setup is the C++ one (lazy as mgpbd's: a values-only refresh
    until amg.setup_interval frames have passed), its levels then copied to the device."""

    name = "mgpbd-gpu"

    def __init__(self, backend="auto", max_iterations=1000, **amg_settings):
        self.backend = Backend(backend)
        self.max_iterations = int(max_iterations)
        self.settings = _settings(amg_settings)
        from . import parameters  # refuse an unknown key now, not at the first setup
        known = {p["key"] for p in parameters()}
        for key in self.settings:
            if key not in known:
                raise ValueError(f"MgpbdGpu: unknown setting '{key}' (amg.* keys of `xpbd-bench list`, and seed)")
        self.hierarchy = self.device = self.A = None
        self.last_frame, self.pattern, self.iterations = 0, None, []
        self.setups = self.refreshes = 0  # full C++ setups, values-only refreshes

    def setup(self, A, info):
        from . import amg_hierarchy  # the C++ setup (needs the built module)
        pattern = (A.shape, A.nnz, info["block_size"])
        interval = int(self.settings.get("amg.setup_interval", 20))
        full = (info["action"] == "setup" or self.hierarchy is None or pattern != self.pattern
                or info["frame"] >= self.last_frame + interval or info["frame"] < self.last_frame)
        if not full and self.hierarchy.refresh(A):
            self.refreshes += 1
        else:
            self.hierarchy = amg_hierarchy(A, info["block_size"], info["near_kernel"], self.settings)
            self.pattern, self.last_frame = pattern, info["frame"]
            self.setups += 1
        self.device = DeviceHierarchy(self.hierarchy.export(), self.backend)
        self.A = self.backend.csr(A, np.float64)
        self.backend.synchronize()

    def solve(self, b, tol):
        be = self.backend
        x, its, _ = pcg(self.A, be.array(b, np.float64), self.device.vcycle, tol, self.max_iterations, be.xp)
        be.synchronize()  # the harness's clock reads after this returns
        self.iterations.append(its)
        return be.host(x), its
