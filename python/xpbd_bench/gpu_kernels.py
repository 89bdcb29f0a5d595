"""The device operations of mgpbd's solve phase (python/xpbd_bench/gpu.py), each one kernel launch
on a device: CuPy RawKernels (the CUDA source below) or one CuPy call (astype, a dense gemv), and
the same operations on NumPy/SciPy, what CI runs. Both count what they would launch (`launches`)
and the blocking reads of device scalars by the host (`syncs`), so the count per PCG iteration is
measured, and tested, without a device.

What is fused (unfused, one PCG iteration at 270K was ~150-200 launches and 4-5 host syncs):
 - a smoother step d = c1*d + c2*D^-1(b - A x), x_out = x + d in one kernel, a thread per node
   (D^-1 by node blocks or scalars); x is double-buffered, as neighbours read x while it changes;
 - PCG's scalars (p^T A p, r^T z, the residual norm, the V-cycle's scale ||b||inf) stay on the
   device in one small array that the update kernels read; the host reads it once per iteration,
   for the stop test;
 - reductions are deterministic: a fixed grid for each length, per-block partial sums in a fixed
   order, the last block to finish adds the partials in block order (no atomics on values).
"""
import numpy as np

# One module per value type (T = float or double); accumulations in double.
CUDA_SOURCE = r"""
__device__ double amax(const double v, const double f) { return (f > v || f != f) ? f : v; }  // NaN sticks

extern "C" {
__global__ void spmv(const int n, const int* ptr, const int* idx, const T* val, const T* x, T* y, const int add) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  T s = 0;
  for (int k = ptr[i]; k < ptr[i + 1]; ++k) s += val[k] * x[idx[k]];
  y[i] = add ? y[i] + s : s;
}
__global__ void residual(const int n, const int* ptr, const int* idx, const T* val, const T* x, const T* b, T* r) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  T s = b[i];
  for (int k = ptr[i]; k < ptr[i + 1]; ++k) s -= val[k] * x[idx[k]];
  r[i] = s;
}
// One node per thread: t = b - A x_in on its rows, u = D_I^-1 t, d = c1 d + c2 u (c1 = 0: d not
// read), x_out = x_in + d. first: x_in = 0 (no product with A, x_out = d).
__global__ void relax_step(const int nodes, const int* node_start, const long* offset, const T* block_inv,
                           const int* ptr, const int* idx, const T* val, const T* b, const T* x_in, T* d,
                           T* x_out, const double c1, const double c2, const int first) {
  const int I = blockDim.x * blockIdx.x + threadIdx.x;
  if (I >= nodes) return;
  const int r0 = node_start[I], m = node_start[I + 1] - r0;
  T t[MAX_NODE];
  for (int a = 0; a < m; ++a) {
    T s = b[r0 + a];
    if (!first)
      for (int k = ptr[r0 + a]; k < ptr[r0 + a + 1]; ++k) s -= val[k] * x_in[idx[k]];
    t[a] = s;
  }
  const T* Di = block_inv + offset[I];
  for (int a = 0; a < m; ++a) {
    T u = 0;
    for (int c = 0; c < m; ++c) u += Di[a * m + c] * t[c];
    const T da = (T)c2 * u + (c1 != 0.0 && !first ? (T)c1 * d[r0 + a] : (T)0);
    d[r0 + a] = da;
    x_out[r0 + a] = first ? da : x_in[r0 + a] + da;
  }
}
// out[slot] = sum a*b (mode 0), its square root (1), or max |a| (2), deterministic (see above).
__global__ void reduce(const long n, const T* a, const T* b, double* partial, unsigned int* done, double* out,
                       const int slot, const int mode) {
  __shared__ double s[256];
  double v = 0;
  for (long i = (long)blockIdx.x * blockDim.x + threadIdx.x; i < n; i += (long)gridDim.x * blockDim.x)
    v = mode == 2 ? amax(v, fabs((double)a[i])) : v + (double)a[i] * (double)b[i];
  s[threadIdx.x] = v;
  __syncthreads();
  for (int w = blockDim.x / 2; w > 0; w /= 2) {
    if (threadIdx.x < w) s[threadIdx.x] = mode == 2 ? amax(s[threadIdx.x], s[threadIdx.x + w]) : s[threadIdx.x] + s[threadIdx.x + w];
    __syncthreads();
  }
  __shared__ bool last;
  if (threadIdx.x == 0) {
    partial[blockIdx.x] = s[0];
    __threadfence();
    last = atomicInc(done, gridDim.x - 1) == gridDim.x - 1;  // the last block resets it to 0
  }
  __syncthreads();
  if (last && threadIdx.x == 0) {
    double t = 0;
    for (unsigned int k = 0; k < gridDim.x; ++k) {
      const double p = ((volatile double*)partial)[k];
      t = mode == 2 ? amax(t, p) : t + p;
    }
    out[slot] = mode == 1 ? sqrt(t) : t;
  }
}
// PCG: alpha = rz / pAp (0 unless pAp > 0 and finite: the host stops on it), x += alpha p, r -= alpha Ap.
__global__ void update_xr(const int n, T* x, T* r, const T* p, const T* Ap, const double* s, const int rz, const int pap) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  const double q = s[pap];
  const double alpha = (q > 0 && isfinite(q)) ? s[rz] / q : 0.0;
  x[i] += alpha * p[i];
  r[i] -= alpha * Ap[i];
}
// PCG: p = z + (rz_new / rz) p.
__global__ void update_p(const int n, T* p, const T* z, const double* s, const int rz_new, const int rz) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  p[i] = z[i] + (s[rz_new] / s[rz]) * p[i];
}
// The float V-cycle's scaling by s = ||b||inf (vcycle.cpp): in: out = b / s (0 where s is not a
// positive number); out: out = s * x, or s itself where s is not finite.
__global__ void scale_in(const int n, const double* b, T* out, const double* s, const int slot) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  const double v = s[slot];
  out[i] = (T)((v > 0 && isfinite(v)) ? b[i] / v : 0.0);
}
__global__ void scale_out(const int n, const T* x, double* out, const double* s, const int slot) {
  const int i = blockDim.x * blockIdx.x + threadIdx.x;
  if (i >= n) return;
  const double v = s[slot];
  out[i] = isfinite(v) ? v * (double)x[i] : v;
}
}
"""
MAX_NODE = 8          # rows of a node the relaxation kernel holds (6 rigid modes per aggregate)
THREADS = 256
REDUCE_BLOCKS = 1024  # the reduction's grid at most: fixed per length, so the sums are too
# Slots of the device scalar array.
SLOTS = 8


class Csr:
    """A CSR matrix's arrays on the backend (int32 indices), its values in one dtype. On NumPy,
    `m` is a scipy matrix sharing them."""

    def __init__(self, xp, m, dtype):
        import scipy.sparse
        m = scipy.sparse.csr_matrix(m)
        self.shape, self.nnz = m.shape, m.nnz
        self.indptr = xp.asarray(m.indptr.astype(np.int32))
        self.indices = xp.asarray(m.indices.astype(np.int32))
        self.data = xp.asarray(m.data.astype(dtype))
        self.m = None
        if xp is np:
            self.m = scipy.sparse.csr_matrix((self.data, self.indices, self.indptr), shape=m.shape, copy=False)


class Ops:
    """The operations, counted. Subclasses implement _spmv, _residual, _relax, _reduce, _update_xr,
    _update_p, _scale_in, _scale_out, astype and gemv; `scalars` is the device scalar array."""

    def __init__(self, xp):
        self.xp = xp
        self.launches = self.syncs = 0
        self.scalars = xp.zeros(SLOTS, dtype=np.float64)

    def reset_counts(self):
        self.launches = self.syncs = 0

    def spmv(self, A, x, y, add=False):
        self.launches += 1
        self._spmv(A, x, y, add)
        return y

    def residual(self, A, x, b, r):
        self.launches += 1
        self._residual(A, x, b, r)
        return r

    def relax(self, S, A, b, x_in, d, x_out, c1, c2):
        """A smoother step (S: the level's D^-1 by nodes); x_in None: from zero."""
        self.launches += 1
        self._relax(S, A, b, x_in, d, x_out, c1, c2)

    def reduce(self, a, b, slot, mode):
        """scalars[slot] = a.b (mode 0), ||a|| (1, b = a) or max |a| (2)."""
        self.launches += 1
        self._reduce(a, b, slot, mode)

    def update_xr(self, x, r, p, Ap, rz, pap):
        self.launches += 1
        self._update_xr(x, r, p, Ap, rz, pap)

    def update_p(self, p, z, rz_new, rz):
        self.launches += 1
        self._update_p(p, z, rz_new, rz)

    def scale_in(self, b, out, slot):
        self.launches += 1
        self._scale_in(b, out, slot)

    def scale_out(self, x, out, slot):
        self.launches += 1
        self._scale_out(x, out, slot)

    def copy(self, src, dst):
        self.launches += 1
        dst[...] = src

    def cast(self, a, dtype):
        self.launches += 1
        return a.astype(dtype)

    def dense_gemv(self, M, b):
        self.launches += 1
        return M @ b

    def read(self):
        """The scalars on the host: the one blocking read of an iteration."""
        self.syncs += 1
        return self._read()


class NumpyOps(Ops):
    def __init__(self):
        super().__init__(np)

    def _spmv(self, A, x, y, add):
        if add:
            y += A.m @ x
        else:
            y[...] = A.m @ x

    def _residual(self, A, x, b, r):
        r[...] = b - A.m @ x

    def _relax(self, S, A, b, x_in, d, x_out, c1, c2):
        t = S.dinv_apply(b if x_in is None else b - A.m @ x_in)
        d[...] = c2 * t if c1 == 0 or x_in is None else c1 * d + c2 * t
        x_out[...] = d if x_in is None else x_in + d

    def _reduce(self, a, b, slot, mode):
        if mode == 2:
            self.scalars[slot] = float(np.max(np.abs(a))) if a.size else 0.0
        else:
            v = float(np.dot(a.astype(np.float64), b.astype(np.float64)))
            self.scalars[slot] = np.sqrt(v) if mode == 1 else v

    def _update_xr(self, x, r, p, Ap, rz, pap):
        q = self.scalars[pap]
        alpha = self.scalars[rz] / q if q > 0 and np.isfinite(q) else 0.0
        x += alpha * p
        r -= alpha * Ap

    def _update_p(self, p, z, rz_new, rz):
        p[...] = z + (self.scalars[rz_new] / self.scalars[rz]) * p

    def _scale_in(self, b, out, slot):
        v = self.scalars[slot]
        out[...] = b / v if v > 0 and np.isfinite(v) else 0.0

    def _scale_out(self, x, out, slot):
        v = self.scalars[slot]
        out[...] = v * x.astype(np.float64) if np.isfinite(v) else v

    def _read(self):
        return self.scalars.copy()


class CupyOps(Ops):
    def __init__(self, cupy):
        super().__init__(cupy)
        self.cp = cupy
        self.modules = {}
        self.partial = cupy.zeros(REDUCE_BLOCKS, dtype=np.float64)
        self.done = cupy.zeros(1, dtype=np.uint32)

    def kernel(self, dtype, name):
        key = np.dtype(dtype).name
        if key not in self.modules:
            src = CUDA_SOURCE.replace("MAX_NODE", str(MAX_NODE))
            self.modules[key] = self.cp.RawModule(code=f"typedef {'float' if key == 'float32' else 'double'} T;\n" + src)
        return self.modules[key].get_function(name)

    @staticmethod
    def grid(n):
        return ((n + THREADS - 1) // THREADS,), (THREADS,)

    def _spmv(self, A, x, y, add):
        n = A.shape[0]
        self.kernel(x.dtype, "spmv")(*self.grid(n), (np.int32(n), A.indptr, A.indices, A.data, x, y, np.int32(add)))

    def _residual(self, A, x, b, r):
        n = A.shape[0]
        self.kernel(x.dtype, "residual")(*self.grid(n), (np.int32(n), A.indptr, A.indices, A.data, x, b, r))

    def _relax(self, S, A, b, x_in, d, x_out, c1, c2):
        first = x_in is None
        args = (np.int32(S.nodes), S.node_start, S.offset, S.block_inv, A.indptr, A.indices, A.data, b,
                x_out if first else x_in, d, x_out, np.float64(c1), np.float64(c2), np.int32(first))
        self.kernel(b.dtype, "relax_step")(*self.grid(S.nodes), args)

    def _reduce(self, a, b, slot, mode):
        n = a.size
        blocks = max(1, min(REDUCE_BLOCKS, (n + THREADS - 1) // THREADS))
        self.kernel(a.dtype, "reduce")((blocks,), (THREADS,), (np.int64(n), a, a if b is None else b, self.partial,
                                                              self.done, self.scalars, np.int32(slot), np.int32(mode)))

    def _update_xr(self, x, r, p, Ap, rz, pap):
        n = x.size
        self.kernel(x.dtype, "update_xr")(*self.grid(n), (np.int32(n), x, r, p, Ap, self.scalars, np.int32(rz), np.int32(pap)))

    def _update_p(self, p, z, rz_new, rz):
        n = p.size
        self.kernel(p.dtype, "update_p")(*self.grid(n), (np.int32(n), p, z, self.scalars, np.int32(rz_new), np.int32(rz)))

    def _scale_in(self, b, out, slot):
        n = b.size
        self.kernel(out.dtype, "scale_in")(*self.grid(n), (np.int32(n), b, out, self.scalars, np.int32(slot)))

    def _scale_out(self, x, out, slot):
        n = x.size
        self.kernel(x.dtype, "scale_out")(*self.grid(n), (np.int32(n), x, out, self.scalars, np.int32(slot)))

    def _read(self):
        return self.scalars.get()


class NodeInverse:
    """A level's D^-1 by nodes on the backend: node_start, the offset of each node's row-major
    block in block_inv (scalar levels: one row per node, block_inv = 1/diag)."""

    def __init__(self, xp, smoother, n, dtype):
        import scipy.sparse
        if smoother.get("node_start") is None:
            start = np.arange(n + 1, dtype=np.int64)
            inv = np.asarray(smoother["inv_diag"], dtype=np.float64)
        else:
            start = np.asarray(smoother["node_start"], dtype=np.int64)
            inv = np.asarray(smoother["block_inv"], dtype=np.float64)
        sizes = np.diff(start)
        if sizes.max(initial=1) > MAX_NODE:
            raise ValueError(f"mgpbd-gpu: a node of {sizes.max()} rows (the relaxation kernel holds {MAX_NODE})")
        self.nodes = len(sizes)
        self.node_start = xp.asarray(start.astype(np.int32))
        self.offset = xp.asarray(np.concatenate([[0], np.cumsum(sizes * sizes)[:-1]]).astype(np.int64))
        self.block_inv = xp.asarray(inv.astype(dtype))
        self.D = None
        if xp is np:  # the same blocks as one block-diagonal CSR matrix, for the vectorised step
            node_of_row = np.repeat(np.arange(self.nodes), sizes)
            row_len = sizes[node_of_row]
            indptr = np.concatenate([[0], np.cumsum(row_len)])
            first = np.repeat(start[node_of_row], row_len)
            within = np.arange(indptr[-1]) - np.repeat(indptr[:-1], row_len)
            self.D = scipy.sparse.csr_matrix((inv.astype(dtype), first + within, indptr), shape=(n, n))

    def dinv_apply(self, t):
        return self.D @ t


def make_ops(backend):
    return CupyOps(backend.xp) if backend.device else NumpyOps()
