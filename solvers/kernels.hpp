// Parallel (OpenMP) sparse and vector kernels on the raw CSR arrays (32-bit column indices).
// The matrix kernels split the rows into one contiguous block per thread with about the same
// number of non-zeros (row_block), so each thread streams its own slice of the values and indices
// once; none allocates (but for the chunk sums' buffer, once per thread: core/reduce.hpp). The
// fused kernels do two jobs in one pass over their operands. Every sum
// (dot, spmv_dot, cg_update) is taken over core/reduce.hpp's fixed chunks: the same bits for any
// thread count (spmv_dot's row blocks are cut on chunk boundaries for that).
#pragma once

#include "../core/sparse.hpp"

namespace xb {

// Loops shorter than this run on one thread: on coarse AMG levels (tens to hundreds of rows) and
// in small colour classes a parallel region costs more than the work it splits.
constexpr long kMinParallelRows = 2048;

// Rows [lo, hi) of thread t of T for a CSR row pointer `outer` of n rows: contiguous blocks
// holding about nnz/T non-zeros each.
void row_block(const int* outer, int n, int t, int T, int& lo, int& hi);

// Σ_k val[k]·x[cols[k]] over row i, summed in the storage precision S (the float V-cycle's rows of
// ~10–100 terms are accurate to ~1e-6, as a preconditioner needs, with no conversion per non-zero).
template <class S>
inline S row_dot(const int* outer, const int* cols, const S* val, const S* x, int i) {
  S s = 0;
  for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * x[cols[k]];
  return s;
}

// y = A x
void spmv(const SparseMatrix& A, const Vector& x, Vector& y);
// y = A x, returning x·y (PCG's A p and pᵀA p in one pass).
double spmv_dot(const SparseMatrix& A, const Vector& x, Vector& y);
// r = b − A x
void residual(const SparseMatrix& A, const Vector& x, const Vector& b, Vector& r);
double dot(const Vector& a, const Vector& b);
inline double norm2(const Vector& a) { return std::sqrt(dot(a, a)); }
// y += a x
void axpy(double a, const Vector& x, Vector& y);
// PCG's update x += α p, r −= α A p, returning rᵀr of the new r (one pass over the four vectors).
double cg_update(double alpha, const Vector& p, const Vector& Ap, Vector& x, Vector& r);
// The diagonal of A (zero where a row has no diagonal entry).
Vector diagonal(const SparseMatrix& A);
// 1/A_ii (0 where A_ii ≤ 0: such a row is left alone rather than blown up).
Vector inverse_diagonal(const SparseMatrix& A);

}  // namespace xb
