#include "zero_filter.hpp"

#include "../../core/error.hpp"

#include <string>

namespace xb::amg {

double ZeroBlockFilter::block_norm(const SparseMatrix& A, int I, int k) const {
  const int* ao = A.outerIndexPtr();
  const double* av = A.valuePtr();
  const int w = p_.cols(p_.col[k]);
  double s = 0;
  for (int r = p_.row_start[I]; r < p_.row_start[I + 1]; ++r)
    for (int q = 0; q < w; ++q) s += av[ao[r] + p_.offset[k] + q] * av[ao[r] + p_.offset[k] + q];
  return std::sqrt(s);
}

std::vector<double> ZeroBlockFilter::diagonal_norms(const SparseMatrix& A) const {
  const int nn = p_.row_nodes();
  std::vector<double> d(nn);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I) d[I] = block_norm(A, I, diag_block_[I]);
  return d;
}

bool ZeroBlockFilter::build(const SparseMatrix& A, const BlockPattern& p, double tol) {
  if (p.row_start != p.col_start) throw Error("amg.drop_tolerance: the level's row and column nodes differ");
  p_ = p;
  tol_ = tol;
  source_nnz_ = A.nonZeros();
  const int nn = p_.row_nodes();
  diag_block_.assign(nn, -1);
  for (int I = 0; I < nn; ++I) {
    for (int k = p_.ptr[I]; k < p_.ptr[I + 1]; ++k)
      if (p_.col[k] == I) diag_block_[I] = k;
    if (diag_block_[I] < 0) throw Error("amg.drop_tolerance: node " + std::to_string(I) + " has no diagonal block");
  }
  const std::vector<double> dnorm = diagonal_norms(A);

  // Per row node: which blocks go, and the kept row length.
  std::vector<char> keep(p_.col.size(), 1);
  std::vector<int> dropped(nn + 1, 0), width(nn, 0);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I)
    for (int k = p_.ptr[I]; k < p_.ptr[I + 1]; ++k) {
      double norm;
      if (p_.col[k] != I && negligible(A, I, k, dnorm, norm)) {
        keep[k] = 0;
        ++dropped[I + 1];
      } else {
        width[I] += p_.cols(p_.col[k]);
      }
    }
  for (int I = 0; I < nn; ++I) dropped[I + 1] += dropped[I];
  if (dropped[nn] == 0) {
    *this = ZeroBlockFilter{};
    return false;
  }
  drop_ptr_ = dropped;
  drop_block_.assign(dropped[nn], 0);
  const int n = static_cast<int>(A.rows());
  F_.resize(n, n);
  int* fo = F_.outerIndexPtr();
  fo[0] = 0;
  for (int I = 0; I < nn; ++I)
    for (int r = p_.row_start[I]; r < p_.row_start[I + 1]; ++r) fo[r + 1] = fo[r] + width[I];
  F_.resizeNonZeros(fo[n]);
  source_.assign(fo[n], 0);
  diag_.assign(n, -1);
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  int* fc = F_.innerIndexPtr();
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I) {
    int d = drop_ptr_[I];
    for (int k = p_.ptr[I]; k < p_.ptr[I + 1]; ++k)
      if (!keep[k]) drop_block_[d++] = k;
    for (int r = p_.row_start[I]; r < p_.row_start[I + 1]; ++r) {
      int at = fo[r];
      for (int k = p_.ptr[I]; k < p_.ptr[I + 1]; ++k) {
        if (!keep[k]) continue;
        for (int q = 0; q < p_.cols(p_.col[k]); ++q, ++at) {
          source_[at] = ao[r] + p_.offset[k] + q;
          fc[at] = ac[source_[at]];
          if (fc[at] == r) diag_[r] = at;
        }
      }
    }
  }
  refresh(A);
  return true;
}

bool ZeroBlockFilter::refresh(const SparseMatrix& A) {
  if (A.nonZeros() != source_nnz_) throw Error("amg.drop_tolerance: refresh with a different sparsity pattern");
  const std::vector<double> dnorm = diagonal_norms(A);
  const double* av = A.valuePtr();
  double* fv = F_.valuePtr();
  const int nn = p_.row_nodes();
  int alive = 0;
#pragma omp parallel for schedule(static) reduction(+ : alive)
  for (int I = 0; I < nn; ++I) {
    double lump = 0, norm;
    for (int d = drop_ptr_[I]; d < drop_ptr_[I + 1]; ++d) {
      if (!negligible(A, I, drop_block_[d], dnorm, norm)) ++alive;
      lump += norm;
    }
    for (int r = p_.row_start[I]; r < p_.row_start[I + 1]; ++r) {
      for (int e = F_.outerIndexPtr()[r]; e < F_.outerIndexPtr()[r + 1]; ++e) fv[e] = av[source_[e]];
      fv[diag_[r]] += lump;
    }
  }
  return alive == 0;
}

}  // namespace xb::amg
