#include "smoothed_prolongator.hpp"

#include "../../core/error.hpp"
#include "../kernels.hpp"
#include "block_sparse.hpp"
#include "galerkin.hpp"
#include "relaxation/block_diagonal.hpp"
#include "relaxation/lanczos.hpp"
#include "relaxation/smoothers.hpp"

#include <algorithm>
#include <cmath>
#include <omp.h>

namespace xb::amg {

SparseMatrix transpose(const SparseMatrix& A) {
  const int n = static_cast<int>(A.rows()), m = static_cast<int>(A.cols());
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const double* av = A.valuePtr();
  SparseMatrix T(m, n);
  T.resizeNonZeros(static_cast<int>(A.nonZeros()));
  int* to = T.outerIndexPtr();
  int* tc = T.innerIndexPtr();
  double* tv = T.valuePtr();
  // A counting sort by column, parallel over row blocks: thread t counts its rows' entries per
  // column, then writes them after those of threads < t. Rows stay in increasing order within
  // every column of T (sorted columns), as a serial pass would leave them.
  std::vector<std::vector<int>> start;
#pragma omp parallel
  {
    const int t = omp_get_thread_num(), nt = omp_get_num_threads();
#pragma omp single
    start.assign(nt, std::vector<int>(m + 1, 0));
    int lo, hi;
    row_block(ao, n, t, nt, lo, hi);
    std::vector<int>& mine = start[t];
    for (int k = ao[lo]; k < ao[hi]; ++k) ++mine[ac[k]];
#pragma omp barrier
#pragma omp single
    {
      // Column j of T: to[j], then thread 0's entries, thread 1's, ...
      to[0] = 0;
      for (int j = 0; j < m; ++j) {
        int at = to[j];
        for (int u = 0; u < nt; ++u) {
          const int c = start[u][j];
          start[u][j] = at;
          at += c;
        }
        to[j + 1] = at;
      }
    }
    for (int i = lo; i < hi; ++i)
      for (int k = ao[i]; k < ao[i + 1]; ++k) {
        const int at = mine[ac[k]]++;
        tc[at] = i;
        tv[at] = av[k];
      }
  }
  return T;
}

namespace {
// Y = D⁻¹X with D's node blocks: rows of one node take the union of their patterns.
SparseMatrix block_scale_rows(const BlockDiagonal& D, const SparseMatrix& X) {
  const int nn = D.num_nodes(), m = static_cast<int>(X.cols());
  const int *xo = X.outerIndexPtr(), *xc = X.innerIndexPtr();
  const double* xv = X.valuePtr();
  std::vector<std::vector<int>> cols(nn);
  std::vector<std::vector<double>> vals(nn);  // node I: b_I rows × |cols| (row-major)
#pragma omp parallel
  {
    std::vector<int> pos(m, -1);
#pragma omp for schedule(dynamic, 256)
    for (int I = 0; I < nn; ++I) {
      const int s = D.node_begin(I), b = D.node_end(I) - s;
      std::vector<int>& c = cols[I];
      for (int r = s; r < s + b; ++r)
        for (int k = xo[r]; k < xo[r + 1]; ++k)
          if (pos[xc[k]] < 0) {
            pos[xc[k]] = 0;
            c.push_back(xc[k]);
          }
      std::sort(c.begin(), c.end());
      const int nc = static_cast<int>(c.size());
      for (int q = 0; q < nc; ++q) pos[c[q]] = q;
      std::vector<double>& v = vals[I];
      v.assign(static_cast<size_t>(b) * nc, 0.0);
      for (int t = 0; t < b; ++t)  // source row s + t adds D⁻¹(r, t)·X(s + t, :) to every row r
        for (int k = xo[s + t]; k < xo[s + t + 1]; ++k)
          for (int r = 0; r < b; ++r) v[static_cast<size_t>(r) * nc + pos[xc[k]]] += D.inverse(I, r, t) * xv[k];
      for (int J : c) pos[J] = -1;
    }
  }
  SparseMatrix Y(X.rows(), m);
  int* yo = Y.outerIndexPtr();
  yo[0] = 0;
  for (int I = 0; I < nn; ++I)
    for (int r = D.node_begin(I); r < D.node_end(I); ++r) yo[r + 1] = yo[r] + static_cast<int>(cols[I].size());
  Y.resizeNonZeros(yo[X.rows()]);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I) {
    const int nc = static_cast<int>(cols[I].size());
    for (int r = D.node_begin(I); r < D.node_end(I); ++r) {
      std::copy(cols[I].begin(), cols[I].end(), Y.innerIndexPtr() + yo[r]);
      const double* src = vals[I].data() + static_cast<size_t>(r - D.node_begin(I)) * nc;
      std::copy(src, src + nc, Y.valuePtr() + yo[r]);
    }
  }
  return Y;
}

// X ← T − ω D⁻¹X in X's storage, X = A·T by node blocks (pattern px; T's blocks pt): per node a
// b × b product with D_I⁻¹ over the node's shared columns, scaled by −ω, then T's blocks added
// where they sit in the row (A's diagonal blocks put every column of T's row into A·T's). The
// values of add_scaled(T, −ω, D⁻¹X) in one pass.
void jacobi_step_by_node_blocks(const BlockDiagonal& D, double omega, const SparseMatrix& T, const BlockPattern& pt,
                                SparseMatrix& X, const BlockPattern& px) {
  const int nn = D.num_nodes();
  const int *xo = X.outerIndexPtr(), *to = T.outerIndexPtr();
  const double* tv = T.valuePtr();
  int missing = 0;
#pragma omp parallel reduction(+ : missing)
  {
    std::vector<double> y;
#pragma omp for schedule(dynamic, 256)
    for (int I = 0; I < nn; ++I) {
      const int s = D.node_begin(I), b = D.node_end(I) - s;
      if (b == 0) continue;
      const int len = xo[s + 1] - xo[s];
      double* x = X.valuePtr() + xo[s];
      y.assign(static_cast<size_t>(b) * len, 0.0);
      for (int r = 0; r < b; ++r)
        for (int t = 0; t < b; ++t) {
          const double d = D.inverse(I, r, t);
          for (int q = 0; q < len; ++q) y[static_cast<size_t>(r) * len + q] += d * x[static_cast<size_t>(t) * len + q];
        }
      for (size_t k = 0; k < y.size(); ++k) x[k] = -omega * y[k];
      for (int k = pt.ptr[I]; k < pt.ptr[I + 1]; ++k) {
        const int *first = px.col.data() + px.ptr[I], *last = px.col.data() + px.ptr[I + 1];
        const int* at = std::lower_bound(first, last, pt.col[k]);
        if (at == last || *at != pt.col[k]) {
          ++missing;
          continue;
        }
        const int xoff = px.offset[at - px.col.data()], toff = pt.offset[k], w = pt.cols(pt.col[k]);
        for (int r = 0; r < b; ++r) {
          double* xr = x + static_cast<size_t>(r) * len + xoff;
          const double* tr = tv + to[s + r] + toff;
          for (int q = 0; q < w; ++q) xr[q] = tr[q] + xr[q];
        }
      }
    }
  }
  if (missing) throw Error("smoothed prolongator: A lacks a diagonal block (A·T does not hold T's pattern)");
}

// C = X + a·Y, patterns merged row by row (sorted columns in, sorted columns out).
SparseMatrix add_scaled(const SparseMatrix& X, double a, const SparseMatrix& Y) {
  const int n = static_cast<int>(X.rows());
  const int *xo = X.outerIndexPtr(), *xc = X.innerIndexPtr(), *yo = Y.outerIndexPtr(), *yc = Y.innerIndexPtr();
  const double *xv = X.valuePtr(), *yv = Y.valuePtr();
  std::vector<int> rowptr(n + 1, 0);
  auto merge = [&](int i, int* cc, double* cv) {
    int p = xo[i], q = yo[i], cnt = 0;
    while (p < xo[i + 1] || q < yo[i + 1]) {
      const int end = static_cast<int>(X.cols());
      const int cx = p < xo[i + 1] ? xc[p] : end, cy = q < yo[i + 1] ? yc[q] : end;
      const int c = std::min(cx, cy);
      double v = 0;
      if (cx == c) v += xv[p++];
      if (cy == c) v += a * yv[q++];
      if (cc) {
        cc[cnt] = c;
        cv[cnt] = v;
      }
      ++cnt;
    }
    return cnt;
  };
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) rowptr[i + 1] = merge(i, nullptr, nullptr);
  for (int i = 0; i < n; ++i) rowptr[i + 1] += rowptr[i];
  SparseMatrix C(n, X.cols());
  C.resizeNonZeros(rowptr[n]);
  std::copy(rowptr.begin(), rowptr.end(), C.outerIndexPtr());
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) merge(i, C.innerIndexPtr() + rowptr[i], C.valuePtr() + rowptr[i]);
  return C;
}

// Y ← X + a·Y in Y's storage, when every row of Y holds X's columns (A·T holds T's pattern when A
// stores its diagonal): no merge, no new matrix, the same values as add_scaled. False, and Y
// untouched, otherwise.
bool add_scaled_in_place(const SparseMatrix& X, double a, SparseMatrix& Y) {
  const int n = static_cast<int>(X.rows());
  const int *xo = X.outerIndexPtr(), *xc = X.innerIndexPtr(), *yo = Y.outerIndexPtr(), *yc = Y.innerIndexPtr();
  int missing = 0;
#pragma omp parallel for schedule(static) reduction(+ : missing)
  for (int i = 0; i < n; ++i)
    for (int p = xo[i], q = yo[i]; p < xo[i + 1]; ++p, ++q) {
      while (q < yo[i + 1] && yc[q] < xc[p]) ++q;
      if (q == yo[i + 1] || yc[q] != xc[p]) {
        ++missing;
        break;
      }
    }
  if (missing) return false;
  double* yv = Y.valuePtr();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    for (int q = yo[i]; q < yo[i + 1]; ++q) yv[q] *= a;
    for (int p = xo[i], q = yo[i]; p < xo[i + 1]; ++p, ++q) {
      while (yc[q] < xc[p]) ++q;
      yv[q] = X.valuePtr()[p] + yv[q];
    }
  }
  return true;
}
}  // namespace

long drop_small_blocks(SparseMatrix& P, const NodeLayout& fine, const NodeLayout& coarse, double tol) {
  BlockPattern pp;
  const bool blocks = !fine.scalar() && !coarse.scalar() && pp.build(P, fine, coarse);
  if (!blocks) {  // entries: the pattern of one-row nodes and one-column nodes
    pp = BlockPattern{};
    const int n = static_cast<int>(P.rows()), m = static_cast<int>(P.cols());
    for (int i = 0; i <= n; ++i) pp.row_start.push_back(i);
    for (int j = 0; j <= m; ++j) pp.col_start.push_back(j);
    pp.ptr.assign(P.outerIndexPtr(), P.outerIndexPtr() + n + 1);
    pp.col.assign(P.innerIndexPtr(), P.innerIndexPtr() + P.nonZeros());
    pp.offset.resize(P.nonZeros());
    for (int i = 0; i < n; ++i)
      for (int k = pp.ptr[i]; k < pp.ptr[i + 1]; ++k) pp.offset[k] = k - pp.ptr[i];
  }
  const int nr = pp.row_nodes();
  const int* po = P.outerIndexPtr();
  const double* pv = P.valuePtr();
  std::vector<char> keep(pp.col.size(), 1);
  std::vector<int> len(nr, 0);  // the kept scalar row length of each row node
  long dropped = 0;
#pragma omp parallel for schedule(static) reduction(+ : dropped)
  for (int I = 0; I < nr; ++I) {
    const int s = pp.row_start[I], b = pp.rows(I);
    if (b == 0) continue;
    double big = 0;
    std::vector<double> norm2(pp.ptr[I + 1] - pp.ptr[I], 0.0);
    for (int k = pp.ptr[I]; k < pp.ptr[I + 1]; ++k) {
      double& v = norm2[k - pp.ptr[I]];
      for (int r = 0; r < b; ++r)
        for (int c = 0; c < pp.cols(pp.col[k]); ++c) v += std::pow(pv[po[s + r] + pp.offset[k] + c], 2);
      big = std::max(big, v);
    }
    for (int k = pp.ptr[I]; k < pp.ptr[I + 1]; ++k) {
      keep[k] = norm2[k - pp.ptr[I]] >= tol * tol * big;
      if (keep[k]) len[I] += pp.cols(pp.col[k]);
      else dropped += static_cast<long>(b) * pp.cols(pp.col[k]);
    }
  }
  if (dropped == 0) return 0;
  SparseMatrix Q(P.rows(), P.cols());
  int* qo = Q.outerIndexPtr();
  qo[0] = 0;
  for (int I = 0; I < nr; ++I)
    for (int r = pp.row_start[I]; r < pp.row_start[I + 1]; ++r) qo[r + 1] = qo[r] + len[I];
  Q.resizeNonZeros(qo[P.rows()]);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nr; ++I)
    for (int r = pp.row_start[I]; r < pp.row_start[I + 1]; ++r) {
      int at = qo[r];
      for (int k = pp.ptr[I]; k < pp.ptr[I + 1]; ++k) {
        if (!keep[k]) continue;
        const int w = pp.cols(pp.col[k]), c0 = pp.col_start[pp.col[k]];
        for (int c = 0; c < w; ++c, ++at) {
          Q.innerIndexPtr()[at] = c0 + c;
          Q.valuePtr()[at] = pv[po[r] + pp.offset[k] + c];
        }
      }
    }
  take(P, std::move(Q));
  return dropped;
}

SmoothedProlongator smooth_prolongator(const SparseMatrix& A, const SparseMatrix& T, JacobiDiagonal diag,
                                       const NodeLayout& nodes, int lanczos_steps, unsigned seed,
                                       const NodeLayout& coarse_nodes, const ProlongatorReuse& reuse) {
  if (A.rows() != T.rows()) throw Error("smoothed prolongator: A and T do not fit");
  SmoothedProlongator out;
  Vector v;
  // Block levels: A·T by node blocks (block_sparse.hpp), the same matrices as the scalar path.
  BlockPattern own_pa, pt, pat;
  const BlockPattern* pa = reuse.A_pattern;
  if (!pa && own_pa.build(A, nodes, nodes)) pa = &own_pa;
  const bool by_blocks = pa && pt.build(T, nodes, coarse_nodes);
  SparseMatrix AT = by_blocks ? block_product(A, *pa, T, pt, pat) : spgemm(A, T);
  auto set_omega = [&] {
    if (!(out.lambda > 0) || !std::isfinite(out.lambda))
      throw Error("smoothed prolongator: no positive estimate of lambda_max(D^-1 A) (matrix not positive definite?)");
    out.omega = 4.0 / (3.0 * out.lambda);
  };
  if (diag == JacobiDiagonal::Block && !nodes.scalar()) {
    BlockDiagonal own_D;
    if (!reuse.D) own_D.build(A, nodes);
    const BlockDiagonal& D = reuse.D ? *reuse.D : own_D;
    out.lambda = reuse.lambda > 0 ? reuse.lambda : estimate_lambda_max(A, D, v, lanczos_steps, seed);
    set_omega();
    if (by_blocks) {
      jacobi_step_by_node_blocks(D, out.omega, T, pt, AT, pat);
      take(out.P, std::move(AT));
    } else {
      take(out.P, add_scaled(T, -out.omega, block_scale_rows(D, AT)));
    }
  } else {
    const Vector inv_diag = inverse_diagonal(A);
    out.lambda = reuse.lambda > 0 ? reuse.lambda : estimate_lambda_max(A, inv_diag, v, lanczos_steps, seed);
    set_omega();
    const int n = static_cast<int>(AT.rows());
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i)
      for (int k = AT.outerIndexPtr()[i]; k < AT.outerIndexPtr()[i + 1]; ++k) AT.valuePtr()[k] *= inv_diag[i];
    if (by_blocks && add_scaled_in_place(T, -out.omega, AT))
      take(out.P, std::move(AT));
    else
      take(out.P, add_scaled(T, -out.omega, AT));
  }
  take(out.R, transpose(out.P));  // as fast as a block transpose (measured): a counting sort
  return out;
}

}  // namespace xb::amg
