#include "kernels.hpp"

#include "../core/reduce.hpp"

#include <omp.h>

#include <algorithm>

namespace xb {

void row_block(const int* outer, int n, int t, int T, int& lo, int& hi) {
  const long nnz = outer[n];
  auto start = [&](int k) {
    if (k <= 0) return 0;
    if (k >= T) return n;
    const long target = nnz * k / T;
    return static_cast<int>(std::lower_bound(outer, outer + n, target) - outer);
  };
  lo = start(t);
  hi = start(t + 1);
}

namespace {
// y = A x, and (Dot) x·y in the same pass: over spmv's row blocks cut on the nearest chunk
// boundaries, so that x·y is summed per fixed chunk (core/reduce.hpp).
template <bool Dot>
double spmv_impl(const SparseMatrix& A, const Vector& x, Vector& y) {
  const int n = static_cast<int>(A.rows());
  const int* __restrict outer = A.outerIndexPtr();
  const int* __restrict cols = A.innerIndexPtr();
  const double* __restrict val = A.valuePtr();
  y.resize(n);
  const double* __restrict xp = x.data();
  double* __restrict yp = y.data();
  if constexpr (!Dot) {
#pragma omp parallel
    {
      int lo, hi;
      row_block(outer, n, omp_get_thread_num(), omp_get_num_threads(), lo, hi);
      for (int i = lo; i < hi; ++i) yp[i] = row_dot(outer, cols, val, xp, i);
    }
    return 0;
  }
  auto block_start = [&](int t, int T) {
    int lo, hi;
    row_block(outer, n, t, T, lo, hi);
    return lo;
  };
  return deterministic_sums_in_blocks<1>(n, block_start, [&](long lo, long hi, double* acc) {
    double xy = 0;
    for (int i = static_cast<int>(lo); i < static_cast<int>(hi); ++i) {
      yp[i] = row_dot(outer, cols, val, xp, i);
      xy += xp[i] * yp[i];
    }
    acc[0] = xy;
  })[0];
}
}  // namespace

void spmv(const SparseMatrix& A, const Vector& x, Vector& y) { spmv_impl<false>(A, x, y); }

double spmv_dot(const SparseMatrix& A, const Vector& x, Vector& y) { return spmv_impl<true>(A, x, y); }

void residual(const SparseMatrix& A, const Vector& x, const Vector& b, Vector& r) {
  const int n = static_cast<int>(A.rows());
  const int* __restrict outer = A.outerIndexPtr();
  const int* __restrict cols = A.innerIndexPtr();
  const double* __restrict val = A.valuePtr();
  r.resize(n);
  const double* __restrict xp = x.data();
  double* __restrict rp = r.data();
#pragma omp parallel
  {
    int lo, hi;
    row_block(outer, n, omp_get_thread_num(), omp_get_num_threads(), lo, hi);
    for (int i = lo; i < hi; ++i) rp[i] = b[i] - row_dot(outer, cols, val, xp, i);
  }
}

double dot(const Vector& a, const Vector& b) {
  const double *ap = a.data(), *bp = b.data();
  return deterministic_sum(a.size(), [&](long i) { return ap[i] * bp[i]; });
}

void axpy(double a, const Vector& x, Vector& y) {
  const long n = x.size();
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) y[i] += a * x[i];
}

double cg_update(double alpha, const Vector& p, const Vector& Ap, Vector& x, Vector& r) {
  return deterministic_sums<1>(p.size(), [&](long lo, long hi, double* acc) {
    double rr = 0;
    for (long i = lo; i < hi; ++i) {
      x[i] += alpha * p[i];
      const double ri = r[i] - alpha * Ap[i];
      r[i] = ri;
      rr += ri * ri;
    }
    acc[0] = rr;
  })[0];
}

Vector diagonal(const SparseMatrix& A) {
  const int n = static_cast<int>(A.rows());
  Vector d = Vector::Zero(n);
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i)
    for (int k = outer[i]; k < outer[i + 1]; ++k)
      if (cols[k] == i) d[i] = val[k];
  return d;
}

Vector inverse_diagonal(const SparseMatrix& A) {
  Vector d = diagonal(A);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < d.size(); ++i) d[i] = d[i] > 0 ? 1.0 / d[i] : 0.0;
  return d;
}

}  // namespace xb
