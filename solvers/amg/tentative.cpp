#include "tentative.hpp"

#include "../../problems/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb::amg {

Tentative tentative_prolongator(const Aggregates& agg, const Eigen::MatrixXd& B, double drop_tol) {
  const int n = static_cast<int>(agg.aggregate.size());
  const int na = agg.num_aggregates;
  const int K = static_cast<int>(B.cols());
  if (B.rows() != n) throw Error("tentative prolongator: candidates have " + std::to_string(B.rows()) + " rows, matrix " + std::to_string(n));
  if (K < 1) throw Error("tentative prolongator: no candidate vectors");

  // Members of each aggregate in row order (a counting sort: O(n), sequential).
  std::vector<int> mstart(na + 1, 0), members, local(n, -1);
  for (int i = 0; i < n; ++i)
    if (agg.aggregate[i] >= 0) ++mstart[agg.aggregate[i] + 1];
  for (int a = 0; a < na; ++a) mstart[a + 1] += mstart[a];
  members.resize(mstart[na]);
  {
    std::vector<int> pos(mstart.begin(), mstart.end() - 1);
    for (int i = 0; i < n; ++i) {
      const int a = agg.aggregate[i];
      if (a < 0) continue;
      local[i] = pos[a] - mstart[a];
      members[pos[a]++] = i;
    }
  }

  // Per aggregate, modified Gram–Schmidt with one re-orthogonalisation (stable for the few
  // columns we have). Q is stored column-major per aggregate at qbuf[mstart[a]*K ...].
  std::vector<double> qbuf(static_cast<size_t>(mstart[na]) * K, 0.0), rbuf(static_cast<size_t>(na) * K * K, 0.0);
  std::vector<int> ncols(na, 0);
#pragma omp parallel for schedule(dynamic, 64)
  for (int a = 0; a < na; ++a) {
    const int m = mstart[a + 1] - mstart[a];
    double* Q = qbuf.data() + static_cast<size_t>(mstart[a]) * K;  // m × K, column c at Q + c*m
    double* Rm = rbuf.data() + static_cast<size_t>(a) * K * K;       // K × K column-major
    std::vector<double> v(m);
    int kept = 0;
    for (int c = 0; c < K; ++c) {
      double orig = 0;
      for (int t = 0; t < m; ++t) {
        v[t] = B(members[mstart[a] + t], c);
        orig += v[t] * v[t];
      }
      orig = std::sqrt(orig);
      for (int pass = 0; pass < 2; ++pass)
        for (int q = 0; q < kept; ++q) {
          const double* Qq = Q + static_cast<size_t>(q) * m;
          double r = 0;
          for (int t = 0; t < m; ++t) r += Qq[t] * v[t];
          for (int t = 0; t < m; ++t) v[t] -= r * Qq[t];
          Rm[q + c * K] += r;
        }
      double nv = 0;
      for (int t = 0; t < m; ++t) nv += v[t] * v[t];
      nv = std::sqrt(nv);
      if (orig > 0 && nv > drop_tol * orig) {
        double* Qk = Q + static_cast<size_t>(kept) * m;
        for (int t = 0; t < m; ++t) Qk[t] = v[t] / nv;
        Rm[kept + c * K] = nv;
        ++kept;
      }
    }
    ncols[a] = kept;
  }

  Tentative T;
  T.col_start.assign(na + 1, 0);
  for (int a = 0; a < na; ++a) T.col_start[a + 1] = T.col_start[a] + ncols[a];
  const int nc = T.col_start[na];

  // P: row i of aggregate a holds row local[i] of Q_a at columns col_start[a] ...
  std::vector<int> rowptr(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) rowptr[i + 1] = agg.aggregate[i] >= 0 ? ncols[agg.aggregate[i]] : 0;
  for (int i = 0; i < n; ++i) rowptr[i + 1] += rowptr[i];
  T.P.resize(n, nc);
  T.P.resizeNonZeros(rowptr[n]);
  std::copy(rowptr.begin(), rowptr.end(), T.P.outerIndexPtr());
  int* pc = T.P.innerIndexPtr();
  double* pv = T.P.valuePtr();
  int maxrow = 0;
#pragma omp parallel for schedule(static) reduction(max : maxrow)
  for (int i = 0; i < n; ++i) {
    const int a = agg.aggregate[i];
    if (a < 0) continue;
    const int m = mstart[a + 1] - mstart[a];
    const double* Q = qbuf.data() + static_cast<size_t>(mstart[a]) * K;
    for (int q = 0; q < ncols[a]; ++q) {
      pc[rowptr[i] + q] = T.col_start[a] + q;
      pv[rowptr[i] + q] = Q[static_cast<size_t>(q) * m + local[i]];
    }
    maxrow = std::max(maxrow, ncols[a]);
  }
  T.max_row_entries = maxrow;

  // R = Pᵀ: coarse row col_start[a] + q holds column q of Q_a over the members (sorted rows).
  std::vector<int> rptr(nc + 1, 0);
#pragma omp parallel for schedule(static)
  for (int a = 0; a < na; ++a)
    for (int q = 0; q < ncols[a]; ++q) rptr[T.col_start[a] + q + 1] = mstart[a + 1] - mstart[a];
  for (int c = 0; c < nc; ++c) rptr[c + 1] += rptr[c];
  T.R.resize(nc, n);
  T.R.resizeNonZeros(rptr[nc]);
  std::copy(rptr.begin(), rptr.end(), T.R.outerIndexPtr());
  int* rc = T.R.innerIndexPtr();
  double* rv = T.R.valuePtr();
  T.B_coarse.setZero(nc, K);
#pragma omp parallel for schedule(dynamic, 64)
  for (int a = 0; a < na; ++a) {
    const int m = mstart[a + 1] - mstart[a];
    const double* Q = qbuf.data() + static_cast<size_t>(mstart[a]) * K;
    const double* Rm = rbuf.data() + static_cast<size_t>(a) * K * K;
    for (int q = 0; q < ncols[a]; ++q) {
      const int c = T.col_start[a] + q;
      for (int t = 0; t < m; ++t) {
        rc[rptr[c] + t] = members[mstart[a] + t];
        rv[rptr[c] + t] = Q[static_cast<size_t>(q) * m + t];
      }
      for (int k = 0; k < K; ++k) T.B_coarse(c, k) = Rm[q + k * K];
    }
  }
  return T;
}

}  // namespace xb::amg
