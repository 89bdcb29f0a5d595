#include "block_kernels.hpp"

#include "../kernels.hpp"

#include <algorithm>
#include <vector>

namespace xb::amg {

bool BlockOperator::build(const SparseMatrix& A, const NodeLayout& row_nodes, const NodeLayout& col_nodes) {
  pattern = BlockPattern{};
  uniform_rows = uniform_cols = 0;
  BlockPattern p;
  if (!p.build(A, row_nodes, col_nodes)) return false;
  for (const auto* start : {&p.row_start, &p.col_start})
    for (size_t I = 0; I + 1 < start->size(); ++I)
      if ((*start)[I + 1] - (*start)[I] > kMaxNodeSize) return false;
  auto uniform = [](const std::vector<int>& start) {
    const int b = start.size() > 1 ? start[1] - start[0] : 0;
    for (size_t I = 0; I + 1 < start.size(); ++I)
      if (start[I + 1] - start[I] != b || start[I] != static_cast<int>(I) * b) return 0;
    return b;
  };
  max_row_length = 0;
  for (long i = 0; i < A.rows(); ++i)
    max_row_length = std::max(max_row_length, static_cast<int>(A.outerIndexPtr()[i + 1] - A.outerIndexPtr()[i]));
  uniform_rows = uniform(p.row_start);
  uniform_cols = uniform(p.col_start);
  pattern = std::move(p);
  return true;
}

namespace {
// acc[r] += Σ_c v[r·len + c]·x[c] for a bi × bj block (row stride len). BI, BJ > 0: known at
// compile time (K's 3×3, the rigid-mode levels' 6×6, P's 3×6), so the loops unroll.
template <class S, int BI, int BJ>
inline void block_apply(int bi, int bj, const S* __restrict v, int len, const S* __restrict x, S* __restrict acc) {
  const int ni = BI > 0 ? BI : bi, nj = BJ > 0 ? BJ : bj;
  for (int r = 0; r < ni; ++r) {
    S s = 0;
    for (int c = 0; c < nj; ++c) s += v[static_cast<long>(r) * len + c] * x[c];
    acc[r] += s;
  }
}

// acc[0..bi) = A_I x: row node I's rows of A x, block by block (bi = its size, > 0).
template <class S, int BI>
inline void node_apply(const BlockPattern& p, const int* ao, const S* av, const S* x, int I, int bi, S* acc) {
  const int s = p.row_start[I];
  const int len = ao[s + 1] - ao[s];
  const S* row = av + ao[s];
  std::fill(acc, acc + bi, S(0));
  for (int k = p.ptr[I]; k < p.ptr[I + 1]; ++k) {
    const int J = p.col[k], c0 = p.col_start[J], bj = p.col_start[J + 1] - c0;
    const S* v = row + p.offset[k];
    if (bj == 3)
      block_apply<S, BI, 3>(bi, bj, v, len, x + c0, acc);
    else if (bj == 6)
      block_apply<S, BI, 6>(bi, bj, v, len, x + c0, acc);
    else
      block_apply<S, BI, 0>(bi, bj, v, len, x + c0, acc);
  }
}

// The same when every row node has BI rows and every column node BJ columns (K: 3×3; a rigid-mode
// level: 6×6; P: 3×6): block q of node I sits at q·BJ in its rows and x_J at J·BJ, so the only
// index read per block is J, and the node's rows stay in registers.
template <class S, int BI, int BJ>
inline void node_apply_uniform(const int* ptr, const int* col, const int* ao, const S* av, const S* x, int I, S* acc) {
  const int s = I * BI;
  const long len = ao[s + 1] - ao[s];
  const S* row = av + ao[s];
  S a[BI] = {};
  for (int k = ptr[I], q = 0; k < ptr[I + 1]; ++k, ++q) {
    const S* v = row + q * BJ;
    const S* xj = x + static_cast<long>(col[k]) * BJ;
    for (int r = 0; r < BI; ++r)
      for (int c = 0; c < BJ; ++c) a[r] += v[r * len + c] * xj[c];
  }
  for (int r = 0; r < BI; ++r) acc[r] = a[r];
}

// The same for the rigid-mode levels' 6×6 blocks, vectorised: x's blocks of node I's columns are
// gathered once into xg (len values, contiguous as the node's rows hold them), then each of the BI rows is one contiguous dot
// product with xg, which the compiler runs in SIMD lanes (the omp simd reduction lets it split
// the sum: the result differs from the sequential sum by round-off only). The gather costs len
// loads per node against BI·len multiply-adds. Measured on squash bunny:270k's level 1 (22,458
// rows, 241 per row, float): a smoother step 2.3 ms against 3.1–3.5 CPU ms unrolled; on K's 3×3
// blocks (39 per row) it was slower than the unrolled kernel (5.4–7.4 against 3.2–3.6), so those
// keep it.
template <class S, int BI, int BJ>
inline void node_apply_gathered(const int* ptr, const int* col, const int* ao, const S* av, const S* x, int I,
                                S* __restrict xg, S* acc) {
  const int s = I * BI;
  const int len = ao[s + 1] - ao[s];
  const S* row = av + ao[s];
  for (int k = ptr[I], q = 0; k < ptr[I + 1]; ++k, q += BJ) {
    const S* xj = x + static_cast<long>(col[k]) * BJ;
    for (int c = 0; c < BJ; ++c) xg[q + c] = xj[c];
  }
  for (int r = 0; r < BI; ++r) {
    const S* __restrict v = row + static_cast<long>(r) * len;
    S a = 0;
#pragma omp simd reduction(+ : a)
    for (int q = 0; q < len; ++q) a += v[q] * xg[q];
    acc[r] = a;
  }
}

// f(I, row0, bi, acc) for every non-empty row node I with acc = A_I x, in parallel over nodes.
template <class S, class F>
void for_each_node_product(const BlockOperator& op, const CsrOf<S>& A, const S* x, F&& f) {
  const BlockPattern& p = op.pattern;
  const int nr = p.row_nodes();
  const int* ao = A.outerIndexPtr();
  const S* av = A.valuePtr();
  const int *ptr = p.ptr.data(), *col = p.col.data();
  const int ui = op.uniform_rows, uj = op.uniform_cols;
#pragma omp parallel if (A.rows() > kMinParallelRows)
  {
  // The gather buffer, per thread and kept between calls: no allocation per pass (the block
  // Lanczos of a small level runs many short ones).
  thread_local std::vector<S> xg;
  if (ui == 6 && uj == 6 && static_cast<int>(xg.size()) < op.max_row_length) xg.resize(op.max_row_length);
#pragma omp for schedule(static)
  for (int I = 0; I < nr; ++I) {
    const int bi = p.rows(I);
    if (bi == 0) continue;
    S acc[BlockOperator::kMaxNodeSize];
    if (ui == 6 && uj == 6)
      node_apply_gathered<S, 6, 6>(ptr, col, ao, av, x, I, xg.data(), acc);
    else if (ui == 3 && uj == 3)
      node_apply_uniform<S, 3, 3>(ptr, col, ao, av, x, I, acc);
    else if (ui == 3 && uj == 6)
      node_apply_uniform<S, 3, 6>(ptr, col, ao, av, x, I, acc);
    else if (ui == 6 && uj == 3)
      node_apply_uniform<S, 6, 3>(ptr, col, ao, av, x, I, acc);
    else if (bi == 3)
      node_apply<S, 3>(p, ao, av, x, I, bi, acc);
    else if (bi == 6)
      node_apply<S, 6>(p, ao, av, x, I, bi, acc);
    else
      node_apply<S, 0>(p, ao, av, x, I, bi, acc);
    f(I, p.row_start[I], bi, acc);
  }
  }
}
}  // namespace

template <class S>
void block_residual(const BlockOperator& op, const CsrOf<S>& A, const S* x, const S* b, S* r) {
  for_each_node_product(op, A, x, [&](int, int s, int bi, const S* acc) {
    for (int q = 0; q < bi; ++q) r[s + q] = b[s + q] - acc[q];
  });
}

template <class S>
void block_multiply(const BlockOperator& op, const CsrOf<S>& A, const S* x, S* y, bool add) {
  for_each_node_product(op, A, x, [&](int, int s, int bi, const S* acc) {
    for (int q = 0; q < bi; ++q) y[s + q] = add ? y[s + q] + acc[q] : acc[q];
  });
}

template <class S>
void block_relax_step(const BlockOperator& op, const CsrOf<S>& A, const S* block_inv, const long* offset, const S* b,
                      const S* x, double c1, double c2, S* d) {
  for_each_node_product(op, A, x, [&](int I, int s, int bi, S* acc) {
    for (int q = 0; q < bi; ++q) acc[q] = b[s + q] - acc[q];
    const S* M = block_inv + offset[I];
    for (int r = 0; r < bi; ++r) {
      double m = 0;
      for (int q = 0; q < bi; ++q) m += static_cast<double>(M[r * bi + q]) * acc[q];
      d[s + r] = static_cast<S>(c1 == 0 ? c2 * m : c1 * d[s + r] + c2 * m);
    }
  });
}

#define XB_BLOCK_KERNELS(S)                                                                                \
  template void block_residual<S>(const BlockOperator&, const CsrOf<S>&, const S*, const S*, S*);          \
  template void block_multiply<S>(const BlockOperator&, const CsrOf<S>&, const S*, S*, bool);              \
  template void block_relax_step<S>(const BlockOperator&, const CsrOf<S>&, const S*, const long*, const S*, \
                                    const S*, double, double, S*);
XB_BLOCK_KERNELS(double)
XB_BLOCK_KERNELS(float)
#undef XB_BLOCK_KERNELS

}  // namespace xb::amg
