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

from .gpu_kernels import Csr, NodeInverse, make_ops

# The device scalars' slots (gpu_kernels.SLOTS): the V-cycle's ‖b‖∞, PCG's ‖b‖, p'Ap, the
# residual norm, and r'z in two slots (the new one is written while the old one is still read).
SCALE, BNORM, PAP, RNORM, RZ = 0, 1, 2, 3, (4, 5)


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
        self.ops = make_ops(self)  # the solve phase's operations, counted (gpu_kernels.py)

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


class _Level:
    """A level on the backend: A (and P, R to the next level) in the V-cycle's dtype, D⁻¹ by nodes,
    and its work vectors (b, r, d; x double-buffered: a smoother step reads x while it writes the
    next one)."""

    def __init__(self, be, level, dtype):
        xp = be.xp
        self.A = Csr(xp, level["A"], dtype)
        self.P = Csr(xp, level["P"], dtype) if level.get("P") is not None else None
        self.R = Csr(xp, level["R"], dtype) if level.get("R") is not None else None
        n = self.A.shape[0]
        self.b, self.r, self.d = (xp.zeros(n, dtype) for _ in range(3))
        self.xs, self.cur = [xp.zeros(n, dtype), xp.zeros(n, dtype)], 0  # x is xs[cur]
        s = level.get("smoother")
        self.steps, self.sweeps, self.S = [], 0, None
        if s is None:
            return
        if not s["polynomial"]:
            raise ValueError(f"mgpbd-gpu runs the polynomial smoothers (jacobi, chebyshev, block_jacobi, "
                             f"block_chebyshev), not amg.smoother={s['kind']}")
        self.steps = [(float(c1), float(c2)) for c1, c2 in np.asarray(s["steps"]).reshape(-1, 2)]
        self.sweeps = int(s["sweeps"])
        self.S = NodeInverse(xp, s, n, dtype)

    @property
    def x(self):
        return self.xs[self.cur]

    def smooth(self, ops, b, from_zero):
        """`sweeps` sweeps of the steps: d = c1·d + c2·D⁻¹(b − A x), x += d, one launch each
        (from_zero: x = 0 on entry, the first step reads b only). Returns x."""
        if from_zero:
            self.cur = 0
        for _ in range(self.sweeps):
            for c1, c2 in self.steps:
                ops.relax(self.S, self.A, b, None if from_zero else self.x, self.d, self.xs[1 - self.cur], c1, c2)
                self.cur, from_zero = 1 - self.cur, False
        return self.x


class DeviceHierarchy:
    """The exported levels (a dict: AmgHierarchy.export() or gpu_bench's read from a capture) on
    the backend; vcycle(b) is Hierarchy::vcycle in the backend's counted operations (ops)."""

    def __init__(self, export, backend):
        self.be = be = backend
        self.ops = backend.ops
        self.precision = export["precision"]
        self.dtype = np.float32 if self.precision == "single" else np.float64
        self.coarse_solver = export["coarse_solver"]
        levels = export["levels"]
        self.levels = [_Level(be, L, self.dtype) for L in levels[:-1]]
        self.rows = [int(L["A"].shape[0]) for L in levels]
        self.nnz = [int(L["A"].nnz) for L in levels]
        self.coarse_b = be.xp.zeros(self.rows[-1], self.dtype)
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
        """The coarsest solve in double of b (in the V-cycle's dtype); x in the V-cycle's dtype."""
        ops = self.ops
        b64 = b if b.dtype == np.float64 else ops.cast(b, np.float64)
        if self.coarse_level is not None:
            x = self.coarse_level.smooth(ops, b64, True)
        elif self.coarse_inv is not None:
            x = ops.dense_gemv(self.coarse_inv, b64)
        else:
            ops.syncs += 1  # a solve on the host
            x = self.be.array(self.coarse_lu.solve(self.be.host(b64)), np.float64)
        return x if x.dtype == self.dtype else ops.cast(x, self.dtype)

    def vcycle(self, b, out=None):
        """One V-cycle from x = 0 (Algorithm 2) of a double vector b, into out (double; new if
        None). The float V-cycle runs on b/‖b‖∞ and scales back (vcycle.cpp), ‖b‖∞ staying on
        the device."""
        ops, xp = self.ops, self.be.xp
        out = xp.empty_like(b) if out is None else out
        if not self.levels:
            ops.copy(self.coarse(b), out)
            return out
        L0 = self.levels[0]
        if self.dtype == np.float32:
            ops.reduce(b, None, SCALE, 2)
            ops.scale_in(b, L0.b, SCALE)
        else:
            ops.copy(b, L0.b)
        for l, L in enumerate(self.levels):
            L.smooth(ops, L.b, True)
            ops.residual(L.A, L.x, L.b, L.r)
            ops.spmv(L.R, L.r, self.levels[l + 1].b if l + 1 < len(self.levels) else self.coarse_b)
        xc = self.coarse(self.coarse_b)
        for L in reversed(self.levels):
            ops.spmv(L.P, xc, L.x, add=True)
            xc = L.smooth(ops, L.b, False)
        if self.dtype == np.float32:
            ops.scale_out(xc, out, SCALE)
        else:
            ops.copy(xc, out)
        return out


def pcg(A, b, precond, tol, max_iterations, ops, dual_map=None, dual_scale=1.0, natural_norm=False):
    """solvers/krylov/pcg.cpp's loop on the backend: from x = 0 to ‖r‖₂ ≤ tol·‖b‖₂; with dual_map
    (a Csr G) to ‖G r‖₂/dual_scale ≤ tol (the dual residual of a primal residual); natural_norm:
    √(rᵀM⁻¹r) ≤ tol·√(r₀ᵀM⁻¹r₀). A: a Csr; b: a double vector on the backend; precond(r, z)
    writes M⁻¹r into z. The scalars stay on the device; the host reads them once per iteration
    (twice with natural_norm). Returns (x, iterations, status)."""
    xp = ops.xp
    x, r, z, p, Ap = xp.zeros_like(b), xp.empty_like(b), xp.empty_like(b), xp.empty_like(b), xp.empty_like(b)
    Gr = xp.empty(dual_map.shape[0], dtype=b.dtype) if dual_map is not None else None
    ops.reduce(b, b, BNORM, 1)
    bnorm = float(ops.read()[BNORM])
    if not math.isfinite(bnorm):
        return x, 0, "breakdown"
    if bnorm == 0:
        return x, 0, "converged"
    ops.copy(b, r)
    precond(r, z)
    ops.copy(z, p)
    rz, rz_new = RZ
    ops.reduce(r, z, rz, 0)
    status, its, rz0 = "max_iterations", 0, None
    for k in range(max_iterations):
        ops.spmv(A, p, Ap)
        ops.reduce(p, Ap, PAP, 0)
        ops.update_xr(x, r, p, Ap, rz, PAP)  # a no-op where the host then finds a breakdown
        if Gr is not None:
            ops.spmv(dual_map, r, Gr)
            ops.reduce(Gr, Gr, RNORM, 1)
        else:
            ops.reduce(r, r, RNORM, 1)
        s = ops.read()
        rz0 = s[rz] if rz0 is None else rz0
        if not (s[PAP] > 0) or not math.isfinite(s[PAP]) or not (s[rz] > 0):
            status = "breakdown"
            break
        its = k + 1
        rnorm = s[RNORM] / dual_scale * bnorm if Gr is not None else s[RNORM]
        if not math.isfinite(rnorm):
            status = "breakdown"
            break
        if not natural_norm and rnorm <= tol * bnorm:
            status = "converged"
            break
        precond(r, z)
        ops.reduce(r, z, rz_new, 0)
        if natural_norm:
            v = ops.read()[rz_new]
            if v >= 0 and math.sqrt(v) <= tol * math.sqrt(rz0):
                status = "converged"
                break
        ops.update_p(p, z, rz_new, rz)
        rz, rz_new = rz_new, rz
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
        self.A = Csr(self.backend.xp, A, np.float64)
        self.backend.synchronize()

    def solve(self, b, tol):
        be = self.backend
        x, its, _ = pcg(self.A, be.array(b, np.float64), self.device.vcycle, tol, self.max_iterations, be.ops)
        be.synchronize()  # the harness's clock reads after this returns
        self.iterations.append(its)
        return be.host(x), its
