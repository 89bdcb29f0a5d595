#include "block_sparse.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <omp.h>
#include <string>

namespace xb::amg {

namespace {
// The blocks of row node I in its first row's columns (cs: those columns, len of them): per
// block its column node and offset. False if the columns are not whole column nodes.
bool split_row(const int* cs, int len, const std::vector<int>& node_of_col, const std::vector<int>& col_start,
               int* col, int* offset, int& nb) {
  nb = 0;
  for (int q = 0; q < len;) {
    const int J = node_of_col[cs[q]], b = col_start[J + 1] - col_start[J];
    // Columns are sorted and distinct: first and last of the node present ⇒ all of it.
    if (cs[q] != col_start[J] || q + b > len || cs[q + b - 1] != col_start[J + 1] - 1) return false;
    if (col) {
      col[nb] = J;
      offset[nb] = q;
    }
    ++nb;
    q += b;
  }
  return true;
}

bool layout_fits(const NodeLayout& l, long n) {
  return !l.scalar() && l.node_start.front() == 0 && l.node_start.back() == n;
}
}  // namespace

bool BlockPattern::build(const SparseMatrix& A, const NodeLayout& row_nodes, const NodeLayout& col_nodes) {
  if (!layout_fits(row_nodes, A.rows()) || !layout_fits(col_nodes, A.cols())) return false;
  row_start = row_nodes.node_start;
  col_start = col_nodes.node_start;
  const int nr = static_cast<int>(row_start.size()) - 1, ncn = static_cast<int>(col_start.size()) - 1;
  std::vector<int> node_of_col(A.cols());
  for (int J = 0; J < ncn; ++J) std::fill(node_of_col.begin() + col_start[J], node_of_col.begin() + col_start[J + 1], J);
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  ptr.assign(nr + 1, 0);
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (int I = 0; I < nr; ++I) {
    const int s = row_start[I], e = row_start[I + 1];
    if (s == e) continue;
    const int len = ao[s + 1] - ao[s];
    for (int r = s + 1; r < e; ++r)
      if (ao[r + 1] - ao[r] != len || !std::equal(ac + ao[s], ac + ao[s + 1], ac + ao[r])) ++bad;
    if (!split_row(ac + ao[s], len, node_of_col, col_start, nullptr, nullptr, ptr[I + 1])) ++bad;
  }
  if (bad) return false;
  for (int I = 0; I < nr; ++I) ptr[I + 1] += ptr[I];
  col.resize(ptr[nr]);
  offset.resize(ptr[nr]);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nr; ++I) {
    const int s = row_start[I];
    int nb = 0;
    if (rows(I) > 0)
      split_row(ac + ao[s], ao[s + 1] - ao[s], node_of_col, col_start, col.data() + ptr[I], offset.data() + ptr[I], nb);
  }
  return true;
}

namespace {
// The sorted column nodes of block row I of A·B; mark (per thread, over B's column nodes) is
// stamped with I, so it needs no reset.
void product_row(const BlockPattern& pa, const BlockPattern& pb, int I, std::vector<int>& mark, std::vector<int>& out) {
  out.clear();
  for (int k = pa.ptr[I]; k < pa.ptr[I + 1]; ++k) {
    const int K = pa.col[k];
    for (int t = pb.ptr[K]; t < pb.ptr[K + 1]; ++t)
      if (mark[pb.col[t]] != I) {
        mark[pb.col[t]] = I;
        out.push_back(pb.col[t]);
      }
  }
  std::sort(out.begin(), out.end());
}

// C's CSR row pointers from the scalar length of each row node's rows.
void fill_row_pointers(const BlockPattern& pc, const std::vector<int>& len, SparseMatrix& C) {
  int* co = C.outerIndexPtr();
  co[0] = 0;
  for (int I = 0; I < pc.row_nodes(); ++I)
    for (int r = pc.row_start[I]; r < pc.row_start[I + 1]; ++r) co[r + 1] = co[r] + len[I];
  C.resizeNonZeros(co[C.rows()]);
  std::fill(C.valuePtr(), C.valuePtr() + C.nonZeros(), 0.0);
}
}  // namespace

void block_product_pattern(const BlockPattern& pa, const BlockPattern& pb, SparseMatrix& C, BlockPattern& pc) {
  if (pa.col_start != pb.row_start) throw Error("block product: the inner node layouts differ");
  const int nr = pa.row_nodes(), ncn = static_cast<int>(pb.col_start.size()) - 1;
  pc.row_start = pa.row_start;
  pc.col_start = pb.col_start;
  pc.ptr.assign(nr + 1, 0);
  std::vector<int> len(nr, 0);
#pragma omp parallel
  {
    std::vector<int> mark(ncn, -1), js;
#pragma omp for schedule(dynamic, 8)
    for (int I = 0; I < nr; ++I) {
      product_row(pa, pb, I, mark, js);
      pc.ptr[I + 1] = static_cast<int>(js.size());
      for (int J : js) len[I] += pc.cols(J);
    }
  }
  for (int I = 0; I < nr; ++I) pc.ptr[I + 1] += pc.ptr[I];
  pc.col.resize(pc.ptr[nr]);
  pc.offset.resize(pc.ptr[nr]);
  C.resize(pa.row_start.back(), pb.col_start.back());
  fill_row_pointers(pc, len, C);
  const int* co = C.outerIndexPtr();
  int* cc = C.innerIndexPtr();
#pragma omp parallel
  {
    std::vector<int> mark(ncn, -1), js;
#pragma omp for schedule(dynamic, 8)
    for (int I = 0; I < nr; ++I) {
      product_row(pa, pb, I, mark, js);
      int off = 0;
      for (size_t q = 0; q < js.size(); ++q) {
        pc.col[pc.ptr[I] + q] = js[q];
        pc.offset[pc.ptr[I] + q] = off;
        for (int r = pc.row_start[I]; r < pc.row_start[I + 1]; ++r)
          for (int c = 0; c < pc.cols(js[q]); ++c) cc[co[r] + off + c] = pc.col_start[js[q]] + c;
        off += pc.cols(js[q]);
      }
    }
  }
}

namespace {
// c += a·b for a bi × bk block (stride lda), b bk × bj (ldb), c bi × bj (ldc). BK, BJ > 0: bk, bj
// known at compile time (the usual 3 and 6), so the loops unroll and vectorise.
template <int BK, int BJ>
inline void block_madd(int bi, int bk, int bj, const double* __restrict a, int lda, const double* __restrict b, int ldb,
                       double* __restrict c, int ldc) {
  const int nk = BK > 0 ? BK : bk;
  for (int r = 0; r < bi; ++r) {
    double* cr = c + static_cast<long>(r) * ldc;
    const double* ar = a + static_cast<long>(r) * lda;
    if constexpr (BJ > 0) {
      double acc[BJ];  // c's row in registers over the bk terms (the same sums, the same order)
      for (int q = 0; q < BJ; ++q) acc[q] = cr[q];
      for (int t = 0; t < nk; ++t)
        for (int q = 0; q < BJ; ++q) acc[q] += ar[t] * b[static_cast<long>(t) * ldb + q];
      for (int q = 0; q < BJ; ++q) cr[q] = acc[q];
    } else {
      for (int t = 0; t < nk; ++t)
        for (int q = 0; q < bj; ++q) cr[q] += ar[t] * b[static_cast<long>(t) * ldb + q];
    }
  }
}

inline void block_madd_any(int bi, int bk, int bj, const double* a, int lda, const double* b, int ldb, double* c, int ldc) {
  if (bj == 6 && bk == 3)
    block_madd<3, 6>(bi, bk, bj, a, lda, b, ldb, c, ldc);
  else if (bj == 6 && bk == 6)
    block_madd<6, 6>(bi, bk, bj, a, lda, b, ldb, c, ldc);
  else if (bj == 6)
    block_madd<0, 6>(bi, bk, bj, a, lda, b, ldb, c, ldc);
  else if (bj == 3 && bk == 3)
    block_madd<3, 3>(bi, bk, bj, a, lda, b, ldb, c, ldc);
  else
    block_madd<0, 0>(bi, bk, bj, a, lda, b, ldb, c, ldc);
}

// c_J += a·b_J for the blocks b_J of one row node K of B (blocks t0..t1): a is BI × BK, kept in
// registers across them; blocks of another width than BJ go through block_madd_any. The sums are
// block_madd's, in its order.
template <int BI, int BK, int BJ>
void row_madd(const double* __restrict a, int lda, const double* b0, int ldb, const BlockPattern& pb, int t0, int t1,
              const int* pos, double* c0, int ldc) {
  double ar[BI][BK];
  for (int r = 0; r < BI; ++r)
    for (int k = 0; k < BK; ++k) ar[r][k] = a[static_cast<long>(r) * lda + k];
  for (int t = t0; t < t1; ++t) {
    const int J = pb.col[t];
    const double* __restrict b = b0 + pb.offset[t];
    double* __restrict c = c0 + pos[J];
    if (pb.cols(J) != BJ) {
      block_madd_any(BI, BK, pb.cols(J), a, lda, b, ldb, c, ldc);
      continue;
    }
    for (int r = 0; r < BI; ++r) {
      double* cr = c + static_cast<long>(r) * ldc;
      double acc[BJ];
      for (int q = 0; q < BJ; ++q) acc[q] = cr[q];
      for (int k = 0; k < BK; ++k)
        for (int q = 0; q < BJ; ++q) acc[q] += ar[r][k] * b[static_cast<long>(k) * ldb + q];
      for (int q = 0; q < BJ; ++q) cr[q] = acc[q];
    }
  }
}

// Block row I of C = A·B (C's pattern set; pos: per thread, over C's column nodes); upper: only
// its blocks J ≥ I (B's rows hold sorted column nodes: the loop starts at the first J ≥ I).
void product_block_row(const SparseMatrix& A, const BlockPattern& pa, const SparseMatrix& B, const BlockPattern& pb,
                       SparseMatrix& C, const BlockPattern& pc, int I, std::vector<int>& pos, bool upper) {
  const int s = pa.row_start[I], bi = pa.rows(I);
  const int *ao = A.outerIndexPtr(), *bo = B.outerIndexPtr(), *co = C.outerIndexPtr();
  const int lda = ao[s + 1] - ao[s], ldc = co[s + 1] - co[s];
  double* c0 = C.valuePtr() + co[s];
  std::fill(c0, c0 + static_cast<long>(bi) * ldc, 0.0);
  for (int q = pc.ptr[I]; q < pc.ptr[I + 1]; ++q) pos[pc.col[q]] = pc.offset[q];
  constexpr int kAhead = 2;  // B's rows are gathered by A's column nodes: load them early
  for (int k = pa.ptr[I]; k < pa.ptr[I + 1]; ++k) {
    if (k + kAhead < pa.ptr[I + 1]) {
      const int Kn = pa.col[k + kAhead], sn = pb.row_start[Kn];
      const char* row = reinterpret_cast<const char*>(B.valuePtr() + bo[sn]);
      const long bytes = 8L * (bo[pb.row_start[Kn + 1]] - bo[sn]);
      for (long c = 0; c < bytes; c += 64) __builtin_prefetch(row + c);
      __builtin_prefetch(pb.col.data() + pb.ptr[Kn]);
      __builtin_prefetch(pb.offset.data() + pb.ptr[Kn]);
    }
    const int K = pa.col[k], sk = pb.row_start[K], bk = pb.rows(K);
    const double* a = A.valuePtr() + ao[s] + pa.offset[k];
    const int ldb = bo[sk + 1] - bo[sk];
    const double* b0 = B.valuePtr() + bo[sk];
    const int t0 = upper ? static_cast<int>(std::lower_bound(pb.col.begin() + pb.ptr[K], pb.col.begin() + pb.ptr[K + 1], I) -
                                            pb.col.begin())
                         : pb.ptr[K];
    const int t1 = pb.ptr[K + 1];
    // The usual shapes (K's 3×3 times P's 3×6, R's 6×3 times A·P's 3×6, the 6×6 of level 1) with
    // their sizes known at compile time.
    if (bi == 3 && bk == 3)
      row_madd<3, 3, 6>(a, lda, b0, ldb, pb, t0, t1, pos.data(), c0, ldc);
    else if (bi == 6 && bk == 3)
      row_madd<6, 3, 6>(a, lda, b0, ldb, pb, t0, t1, pos.data(), c0, ldc);
    else if (bi == 6 && bk == 6)
      row_madd<6, 6, 6>(a, lda, b0, ldb, pb, t0, t1, pos.data(), c0, ldc);
    else
      for (int t = t0; t < t1; ++t) {
        const int J = pb.col[t];
        block_madd_any(bi, bk, pb.cols(J), a, lda, b0 + pb.offset[t], ldb, c0 + pos[J], ldc);
      }
  }
}
}  // namespace

void block_product_values(const SparseMatrix& A, const BlockPattern& pa, const SparseMatrix& B, const BlockPattern& pb,
                          SparseMatrix& C, const BlockPattern& pc, const std::vector<int>* mirror) {
  if (A.rows() != C.rows() || B.cols() != C.cols() || pa.col_start != pb.row_start || pc.ptr.size() != pa.ptr.size())
    throw Error("block product: the operands do not fit the cached pattern");
  if (mirror && (mirror->size() != pc.col.size() || pc.row_start != pc.col_start))
    throw Error("block product: the mirror map does not fit the product's pattern");
  const int nr = pa.row_nodes(), ncn = static_cast<int>(pc.col_start.size()) - 1;
  const int* co = C.outerIndexPtr();
  double* cv = C.valuePtr();
#pragma omp parallel
  {
    std::vector<int> pos(ncn, 0);
#pragma omp for schedule(dynamic, 8)
    for (int I = 0; I < nr; ++I)
      if (pa.rows(I) > 0) product_block_row(A, pa, B, pb, C, pc, I, pos, mirror != nullptr);
    if (mirror) {
      // Block (I, J), J < I, is block (J, I) transposed (the implicit barrier above: row J is
      // done); a diagonal block's lower triangle is its upper one's.
#pragma omp for schedule(dynamic, 8)
      for (int I = 0; I < nr; ++I) {
        const auto d = std::lower_bound(pc.col.begin() + pc.ptr[I], pc.col.begin() + pc.ptr[I + 1], I);
        if (d != pc.col.begin() + pc.ptr[I + 1] && *d == I) {
          const int off = pc.offset[d - pc.col.begin()];
          for (int r = 1; r < pc.rows(I); ++r)
            for (int c = 0; c < r; ++c)
              cv[co[pc.row_start[I] + r] + off + c] = cv[co[pc.row_start[I] + c] + off + r];
        }
        for (int q = pc.ptr[I]; q < pc.ptr[I + 1] && pc.col[q] < I; ++q) {
          const int J = pc.col[q], m = (*mirror)[q];
          const double* src = cv + co[pc.row_start[J]] + pc.offset[m];
          const int lds = co[pc.row_start[J] + 1] - co[pc.row_start[J]];
          for (int r = 0; r < pc.rows(I); ++r) {
            double* dst = cv + co[pc.row_start[I] + r] + pc.offset[q];
            for (int c = 0; c < pc.cols(J); ++c) dst[c] = src[static_cast<long>(c) * lds + r];
          }
        }
      }
    }
  }
}

std::vector<int> block_mirror_map(const BlockPattern& pc) {
  if (pc.row_start != pc.col_start) throw Error("block product: a mirror map needs a square node layout");
  std::vector<int> m(pc.col.size(), -1);
  const int nr = pc.row_nodes();
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (int I = 0; I < nr; ++I)
    for (int q = pc.ptr[I]; q < pc.ptr[I + 1] && pc.col[q] < I; ++q) {
      const int J = pc.col[q];
      const auto first = pc.col.begin() + pc.ptr[J], last = pc.col.begin() + pc.ptr[J + 1];
      const auto it = std::lower_bound(first, last, I);
      if (it == last || *it != I)
        ++bad;
      else
        m[q] = static_cast<int>(it - pc.col.begin());
    }
  if (bad) throw Error("block product: the pattern is not symmetric (" + std::to_string(bad) + " blocks without a mirror)");
  return m;
}

SparseMatrix block_product(const SparseMatrix& A, const BlockPattern& pa, const SparseMatrix& B, const BlockPattern& pb,
                           BlockPattern& pc) {
  SparseMatrix C;
  block_product_pattern(pa, pb, C, pc);
  block_product_values(A, pa, B, pb, C, pc);
  return C;
}

}  // namespace xb::amg
