#include "galerkin.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <omp.h>
#include <utility>

namespace xb::amg {

SparseMatrix spgemm(const SparseMatrix& A, const SparseMatrix& B) {
  if (A.cols() != B.rows()) throw Error("spgemm: inner dimensions differ");
  const int n = static_cast<int>(A.rows()), m = static_cast<int>(B.cols());
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const int *bo = B.outerIndexPtr(), *bc = B.innerIndexPtr();
  const double *av = A.valuePtr(), *bv = B.valuePtr();
  std::vector<int> rowptr(n + 1, 0);
  // Symbolic pass: distinct columns per row, with a per-thread marker.
#pragma omp parallel
  {
    std::vector<int> mark(m, -1);
#pragma omp for schedule(dynamic, 256)
    for (int i = 0; i < n; ++i) {
      int cnt = 0;
      for (int k = ao[i]; k < ao[i + 1]; ++k)
        for (int t = bo[ac[k]]; t < bo[ac[k] + 1]; ++t)
          if (mark[bc[t]] != i) {
            mark[bc[t]] = i;
            ++cnt;
          }
      rowptr[i + 1] = cnt;
    }
  }
  for (int i = 0; i < n; ++i) rowptr[i + 1] += rowptr[i];
  SparseMatrix C(n, m);
  C.resizeNonZeros(rowptr[n]);
  std::copy(rowptr.begin(), rowptr.end(), C.outerIndexPtr());
  int* cc = C.innerIndexPtr();
  double* cv = C.valuePtr();
  // Numeric pass: accumulate in a dense per-thread row, then emit sorted columns.
#pragma omp parallel
  {
    std::vector<int> pos(m, -1);
    std::vector<double> acc(m, 0.0);
#pragma omp for schedule(dynamic, 256)
    for (int i = 0; i < n; ++i) {
      int* cols = cc + rowptr[i];
      int cnt = 0;
      for (int k = ao[i]; k < ao[i + 1]; ++k)
        for (int t = bo[ac[k]]; t < bo[ac[k] + 1]; ++t) {
          const int j = bc[t];
          if (pos[j] < 0) {
            pos[j] = cnt;
            cols[cnt++] = j;
            acc[j] = 0;
          }
          acc[j] += av[k] * bv[t];
        }
      std::sort(cols, cols + cnt);
      for (int q = 0; q < cnt; ++q) {
        cv[rowptr[i] + q] = acc[cols[q]];
        pos[cols[q]] = -1;
      }
    }
  }
  return C;
}

SparseMatrix galerkin_product(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P) {
  return spgemm(R, spgemm(A, P));
}

void spgemm_values(const SparseMatrix& A, const SparseMatrix& B, SparseMatrix& C) {
  if (A.cols() != B.rows() || C.rows() != A.rows() || C.cols() != B.cols())
    throw Error("spgemm_values: the product does not fit the cached pattern");
  const int n = static_cast<int>(A.rows()), m = static_cast<int>(B.cols());
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const int *bo = B.outerIndexPtr(), *bc = B.innerIndexPtr();
  const int *co = C.outerIndexPtr(), *cc = C.innerIndexPtr();
  const double *av = A.valuePtr(), *bv = B.valuePtr();
  double* cv = C.valuePtr();
#pragma omp parallel
  {
    // Dense accumulator per thread, summed in spgemm's order, then gathered by C's pattern (which
    // holds every column the product touches, since the patterns are those of the build).
    std::vector<double> acc(m, 0.0);
#pragma omp for schedule(dynamic, 256)
    for (int i = 0; i < n; ++i) {
      for (int q = co[i]; q < co[i + 1]; ++q) acc[cc[q]] = 0;
      for (int k = ao[i]; k < ao[i + 1]; ++k)
        for (int t = bo[ac[k]]; t < bo[ac[k] + 1]; ++t) acc[bc[t]] += av[k] * bv[t];
      for (int q = co[i]; q < co[i + 1]; ++q) cv[q] = acc[cc[q]];
    }
  }
}

void GalerkinProduct::build(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac,
                            const NodeLayout& fine, const NodeLayout& coarse) {
  BlockPattern pr, pa, pp;
  if (pa.build(A, fine, fine) && pp.build(P, fine, coarse) && pr.build(R, coarse, fine)) {
    build(R, A, P, Ac, std::move(pr), std::move(pa), std::move(pp));
    return;
  }
  by_blocks_ = false;
  take(AP_, spgemm(A, P));
  take(Ac, spgemm(R, AP_));
}

void GalerkinProduct::build(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac,
                            BlockPattern pr, BlockPattern pa, BlockPattern pp, bool symmetric) {
  by_blocks_ = true;
  r_ = std::move(pr);
  a_ = std::move(pa);
  p_ = std::move(pp);
  take(AP_, block_product(A, a_, P, p_, ap_));
  block_product_pattern(r_, ap_, Ac, ac_);
  mirror_.clear();
  if (symmetric) mirror_ = block_mirror_map(ac_);
  block_product_values(R, r_, AP_, ap_, Ac, ac_, symmetric ? &mirror_ : nullptr);
}

void GalerkinProduct::refresh(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac) {
  if (AP_.rows() != A.rows() || AP_.cols() != P.cols()) throw Error("Galerkin refresh before build");
  if (!by_blocks_) {
    spgemm_values(A, P, AP_);
    spgemm_values(R, AP_, Ac);
    return;
  }
  block_product_values(A, a_, P, p_, AP_, ap_);
  block_product_values(R, r_, AP_, ap_, Ac, ac_, mirror_.empty() ? nullptr : &mirror_);
}

namespace {
// agg(i) and p_i from P's rows (at most one entry each; a row without one is agg −1).
void aggregate_of_rows(const SparseMatrix& P, std::vector<int>& agg, std::vector<double>& p) {
  const int n = static_cast<int>(P.rows());
  const int *po = P.outerIndexPtr(), *pcol = P.innerIndexPtr();
  const double* pval = P.valuePtr();
  agg.assign(n, -1);
  p.assign(n, 0.0);
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
  for (int i = 0; i < n; ++i) {
    const int cnt = po[i + 1] - po[i];
    if (cnt > 1) ++bad;
    if (cnt == 1) {
      agg[i] = pcol[po[i]];
      p[i] = pval[po[i]];
    }
  }
  if (bad) throw Error("aggregate Galerkin: P has rows with more than one entry (use the general product)");
}

// Per coarse row I: its sorted columns and, per column (count[q] .. count[q+1]), the fine
// non-zeros adding into it (src) with their weights p_i p_j (w).
struct CoarseRows {
  std::vector<std::vector<int>> cols, count, src;
  std::vector<std::vector<double>> w;
};

CoarseRows gather_coarse_rows(const SparseMatrix& A, const SparseMatrix& R, const std::vector<int>& agg,
                              const std::vector<double>& p) {
  const int nc = static_cast<int>(R.rows());
  const int *ao = A.outerIndexPtr(), *acol = A.innerIndexPtr();
  const int *ro = R.outerIndexPtr(), *rcol = R.innerIndexPtr();
  CoarseRows rows;
  auto& rcols = rows.cols;
  auto& rcount = rows.count;
  auto& rsrc = rows.src;
  auto& rw = rows.w;
  rcols.resize(nc);
  rcount.resize(nc);
  rsrc.resize(nc);
  rw.resize(nc);
#pragma omp parallel
  {
    std::vector<int> pos(nc, -1);
    std::vector<int> slot_of;  // per gathered contribution: its local slot
    std::vector<int> ksrc;
    std::vector<double> kw;
#pragma omp for schedule(dynamic, 64)
    for (int I = 0; I < nc; ++I) {
      std::vector<int>& cols = rcols[I];
      slot_of.clear();
      ksrc.clear();
      kw.clear();
      for (int t = ro[I]; t < ro[I + 1]; ++t) {
        const int i = rcol[t];
        for (int k = ao[i]; k < ao[i + 1]; ++k) {
          const int J = agg[acol[k]];
          if (J < 0) continue;
          if (pos[J] < 0) {
            pos[J] = 0;
            cols.push_back(J);
          }
          slot_of.push_back(J);
          ksrc.push_back(k);
          kw.push_back(p[i] * p[acol[k]]);
        }
      }
      std::sort(cols.begin(), cols.end());
      for (int q = 0; q < static_cast<int>(cols.size()); ++q) pos[cols[q]] = q;
      std::vector<int>& count = rcount[I];
      count.assign(cols.size() + 1, 0);
      for (int& J : slot_of) {
        J = pos[J];
        ++count[J + 1];
      }
      for (size_t q = 0; q < cols.size(); ++q) count[q + 1] += count[q];
      rsrc[I].resize(ksrc.size());
      rw[I].resize(ksrc.size());
      std::vector<int> fill(count.begin(), count.end() - 1);
      for (size_t t = 0; t < ksrc.size(); ++t) {
        const int at = fill[slot_of[t]]++;
        rsrc[I][at] = ksrc[t];
        rw[I][at] = kw[t];
      }
      for (int J : cols) pos[J] = -1;
    }
  }
  return rows;
}
}  // namespace

void AggregateGalerkin::build(const SparseMatrix& A, const SparseMatrix& P, const SparseMatrix& R, SparseMatrix& Ac) {
  const int n = static_cast<int>(A.rows()), nc = static_cast<int>(P.cols());
  if (P.rows() != n || R.rows() != nc || R.cols() != n) throw Error("aggregate Galerkin: P, R and A do not fit");
  std::vector<int> agg;
  std::vector<double> p;
  aggregate_of_rows(P, agg, p);
  const CoarseRows rows = gather_coarse_rows(A, R, agg, p);
  const auto& rcols = rows.cols;
  const auto& rcount = rows.count;
  const auto& rsrc = rows.src;
  const auto& rw = rows.w;
  // Concatenate into A_c's CSR and the flat map.
  std::vector<int> rowptr(nc + 1, 0), contrib(nc + 1, 0);
  for (int I = 0; I < nc; ++I) {
    rowptr[I + 1] = rowptr[I] + static_cast<int>(rcols[I].size());
    contrib[I + 1] = contrib[I] + static_cast<int>(rsrc[I].size());
  }
  Ac.resize(nc, nc);
  Ac.resizeNonZeros(rowptr[nc]);
  std::copy(rowptr.begin(), rowptr.end(), Ac.outerIndexPtr());
  slot_start_.assign(rowptr[nc] + 1, 0);
  src_.resize(contrib[nc]);
  weight_.resize(contrib[nc]);
  int* ccol = Ac.innerIndexPtr();
#pragma omp parallel for schedule(dynamic, 64)
  for (int I = 0; I < nc; ++I) {
    const int nq = static_cast<int>(rcols[I].size());
    for (int q = 0; q < nq; ++q) {
      ccol[rowptr[I] + q] = rcols[I][q];
      slot_start_[rowptr[I] + q + 1] = contrib[I] + rcount[I][q + 1];
    }
    std::copy(rsrc[I].begin(), rsrc[I].end(), src_.begin() + contrib[I]);
    std::copy(rw[I].begin(), rw[I].end(), weight_.begin() + contrib[I]);
  }
  fine_nnz_ = A.nonZeros();
  refresh(A, Ac);
}

void AggregateGalerkin::refresh(const SparseMatrix& A, SparseMatrix& Ac) const {
  if (A.nonZeros() != fine_nnz_) throw Error("aggregate Galerkin refresh: the fine pattern changed (setup needed)");
  const double* av = A.valuePtr();
  double* cv = Ac.valuePtr();
  const long ns = static_cast<long>(slot_start_.size()) - 1;
#pragma omp parallel for schedule(static)
  for (long s = 0; s < ns; ++s) {
    double v = 0;
    for (int t = slot_start_[s]; t < slot_start_[s + 1]; ++t) v += weight_[t] * av[src_[t]];
    cv[s] = v;
  }
}

}  // namespace xb::amg
