#include "tentative.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb::amg {

namespace {

// Per aggregate: its members in row order and their thin QR, Q column-major at
// q[start[a]*K ...], R (K × K, column-major) at r[a*K*K ...], `cols` columns kept.
struct AggregateQR {
  int K = 0;
  std::vector<int> start, members, local;  // local[i]: row i's position within its aggregate
  std::vector<double> q, r;
  std::vector<int> cols;
  int size(int a) const { return start[a + 1] - start[a]; }
  const double* Q(int a) const { return q.data() + static_cast<size_t>(start[a]) * K; }
};

// Members of each aggregate in row order (a counting sort: O(n), sequential).
void collect_members(const Aggregates& agg, AggregateQR& qr) {
  const int n = static_cast<int>(agg.aggregate.size()), na = agg.num_aggregates;
  qr.start.assign(na + 1, 0);
  qr.local.assign(n, -1);
  for (int i = 0; i < n; ++i)
    if (agg.aggregate[i] >= 0) ++qr.start[agg.aggregate[i] + 1];
  for (int a = 0; a < na; ++a) qr.start[a + 1] += qr.start[a];
  qr.members.resize(qr.start[na]);
  std::vector<int> pos(qr.start.begin(), qr.start.end() - 1);
  for (int i = 0; i < n; ++i) {
    const int a = agg.aggregate[i];
    if (a < 0) continue;
    qr.local[i] = pos[a] - qr.start[a];
    qr.members[pos[a]++] = i;
  }
}

// Per aggregate, modified Gram–Schmidt with one re-orthogonalisation (stable for the few
// columns we have); a column whose remainder is below drop_tol of its norm is dropped.
void orthonormalise(const Eigen::MatrixXd& B, double drop_tol, AggregateQR& qr) {
  const int na = static_cast<int>(qr.start.size()) - 1, K = qr.K;
  qr.q.assign(static_cast<size_t>(qr.start[na]) * K, 0.0);
  qr.r.assign(static_cast<size_t>(na) * K * K, 0.0);
  qr.cols.assign(na, 0);
#pragma omp parallel for schedule(dynamic, 64)
  for (int a = 0; a < na; ++a) {
    const int m = qr.size(a);
    double* Q = qr.q.data() + static_cast<size_t>(qr.start[a]) * K;  // m × K, column c at Q + c*m
    double* Rm = qr.r.data() + static_cast<size_t>(a) * K * K;       // K × K column-major
    std::vector<double> v(m);
    int kept = 0;
    for (int c = 0; c < K; ++c) {
      double orig = 0;
      for (int t = 0; t < m; ++t) {
        v[t] = B(qr.members[qr.start[a] + t], c);
        orig += v[t] * v[t];
      }
      orig = std::sqrt(orig);
      for (int pass = 0; pass < 2; ++pass)
        for (int k = 0; k < kept; ++k) {
          const double* Qk = Q + static_cast<size_t>(k) * m;
          double r = 0;
          for (int t = 0; t < m; ++t) r += Qk[t] * v[t];
          for (int t = 0; t < m; ++t) v[t] -= r * Qk[t];
          Rm[k + c * K] += r;
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
    qr.cols[a] = kept;
  }
}

// P: row i of aggregate a holds row local[i] of Q_a at columns col_start[a] ...
void assemble_P(const Aggregates& agg, const AggregateQR& qr, Tentative& T) {
  const int n = static_cast<int>(agg.aggregate.size());
  const int nc = T.col_start.back();
  std::vector<int> rowptr(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) rowptr[i + 1] = agg.aggregate[i] >= 0 ? qr.cols[agg.aggregate[i]] : 0;
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
    for (int k = 0; k < qr.cols[a]; ++k) {
      pc[rowptr[i] + k] = T.col_start[a] + k;
      pv[rowptr[i] + k] = qr.Q(a)[static_cast<size_t>(k) * qr.size(a) + qr.local[i]];
    }
    maxrow = std::max(maxrow, qr.cols[a]);
  }
  T.max_row_entries = maxrow;
}

// R = Pᵀ (coarse row col_start[a] + k holds column k of Q_a over the members, sorted rows) and
// the coarse candidates, the stacked R_a.
void assemble_R_and_coarse_candidates(int n, const AggregateQR& qr, Tentative& T) {
  const int na = static_cast<int>(qr.cols.size()), nc = T.col_start.back(), K = qr.K;
  std::vector<int> rptr(nc + 1, 0);
#pragma omp parallel for schedule(static)
  for (int a = 0; a < na; ++a)
    for (int k = 0; k < qr.cols[a]; ++k) rptr[T.col_start[a] + k + 1] = qr.size(a);
  for (int c = 0; c < nc; ++c) rptr[c + 1] += rptr[c];
  T.R.resize(nc, n);
  T.R.resizeNonZeros(rptr[nc]);
  std::copy(rptr.begin(), rptr.end(), T.R.outerIndexPtr());
  int* rc = T.R.innerIndexPtr();
  double* rv = T.R.valuePtr();
  T.B_coarse.setZero(nc, K);
#pragma omp parallel for schedule(dynamic, 64)
  for (int a = 0; a < na; ++a) {
    const int m = qr.size(a);
    const double* Rm = qr.r.data() + static_cast<size_t>(a) * K * K;
    for (int k = 0; k < qr.cols[a]; ++k) {
      const int c = T.col_start[a] + k;
      for (int t = 0; t < m; ++t) {
        rc[rptr[c] + t] = qr.members[qr.start[a] + t];
        rv[rptr[c] + t] = qr.Q(a)[static_cast<size_t>(k) * m + t];
      }
      for (int j = 0; j < K; ++j) T.B_coarse(c, j) = Rm[k + j * K];
    }
  }
}

}  // namespace

Tentative tentative_prolongator(const Aggregates& agg, const Eigen::MatrixXd& B, double drop_tol) {
  const int n = static_cast<int>(agg.aggregate.size());
  const int na = agg.num_aggregates;
  AggregateQR qr;
  qr.K = static_cast<int>(B.cols());
  if (B.rows() != n) throw Error("tentative prolongator: candidates have " + std::to_string(B.rows()) + " rows, matrix " + std::to_string(n));
  if (qr.K < 1) throw Error("tentative prolongator: no candidate vectors");
  collect_members(agg, qr);
  orthonormalise(B, drop_tol, qr);
  Tentative T;
  T.col_start.assign(na + 1, 0);
  for (int a = 0; a < na; ++a) T.col_start[a + 1] = T.col_start[a] + qr.cols[a];
  assemble_P(agg, qr, T);
  assemble_R_and_coarse_candidates(n, qr, T);
  return T;
}

}  // namespace xb::amg
