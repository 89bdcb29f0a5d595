#include "block_diagonal.hpp"

#include "../../problems/error.hpp"
#include "../kernels.hpp"
#include "smoothers.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

namespace xb::amg {

void BlockDiagonal::build(const SparseMatrix& A, const NodeLayout& nodes) {
  const int n = static_cast<int>(A.rows());
  start_ = nodes.scalar() ? NodeLayout::uniform(n, 1).node_start : nodes.node_start;
  if (start_.front() != 0 || start_.back() != n) throw Error("block diagonal: the node layout does not cover the matrix");
  const int nn = num_nodes();
  offset_.assign(nn + 1, 0);
  for (int I = 0; I < nn; ++I) {
    const long b = start_[I + 1] - start_[I];
    offset_[I + 1] = offset_[I] + b * b;
  }
  block_.assign(offset_[nn], 0.0);
  inv_.assign(offset_[nn], 0.0);
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const double* av = A.valuePtr();
  int bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad)
  for (int I = 0; I < nn; ++I) {
    const int s = start_[I], b = start_[I + 1] - s;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Db(block_.data() + offset_[I], b, b);
    for (int r = 0; r < b; ++r) {
      // Sorted columns: the block's entries are one contiguous run of the row.
      const int* first = std::lower_bound(ac + ao[s + r], ac + ao[s + r + 1], s);
      for (const int* k = first; k < ac + ao[s + r + 1] && *k < s + b; ++k) Db(r, *k - s) = av[k - ac];
    }
    Eigen::LLT<Eigen::MatrixXd> llt(Db);
    if (b > 0 && llt.info() != Eigen::Success) {
      bad = std::max(bad, I);
      continue;
    }
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(inv_.data() + offset_[I], b, b) =
        llt.solve(Eigen::MatrixXd::Identity(b, b));
  }
  if (bad >= 0) throw Error("block diagonal: the diagonal block of node " + std::to_string(bad) + " is not positive definite");
}

namespace {
void apply_blocks(const std::vector<int>& start, const std::vector<long>& offset, const std::vector<double>& blocks,
                  const Vector& x, Vector& y) {
  const int nn = static_cast<int>(start.size()) - 1;
  y.resize(x.size());
#pragma omp parallel for schedule(static) if (nn > kMinParallelRows)
  for (int I = 0; I < nn; ++I) {
    const int s = start[I], b = start[I + 1] - s;
    const double* M = blocks.data() + offset[I];
    for (int r = 0; r < b; ++r) {
      double acc = 0;
      for (int c = 0; c < b; ++c) acc += M[r * b + c] * x[s + c];
      y[s + r] = acc;
    }
  }
}
}  // namespace

void BlockDiagonal::apply_inverse(const Vector& x, Vector& y) const { apply_blocks(start_, offset_, inv_, x, y); }
void BlockDiagonal::apply(const Vector& x, Vector& y) const { apply_blocks(start_, offset_, block_, x, y); }

double estimate_lambda_max(const SparseMatrix& A, const BlockDiagonal& D, Vector& v, int iterations, unsigned seed) {
  const long n = A.rows();
  if (n == 0) return 0;
  if (v.size() != n || v.squaredNorm() == 0) {
    std::mt19937_64 rng(seed * 7919ull + 17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    v.resize(n);
    for (long i = 0; i < n; ++i) v[i] = u(rng);
  }
  Vector Dx(n);
  auto dnorm = [&](const Vector& x) {
    D.apply(x, Dx);
    return std::sqrt(std::max(0.0, dot(x, Dx)));
  };
  const int steps = static_cast<int>(std::min<long>(n, std::max(iterations, 10)));
  Vector q = v / dnorm(v), q_prev = Vector::Zero(n), Aq(n), w(n);
  std::vector<double> alpha, beta;
  std::vector<Vector> basis;
  double beta_prev = 0;
  for (int k = 0; k < steps; ++k) {
    basis.push_back(q);
    spmv(A, q, Aq);
    const double a = dot(q, Aq);  // ⟨q, D⁻¹Aq⟩_D
    D.apply_inverse(Aq, w);
    w -= a * q + beta_prev * q_prev;
    const double b = dnorm(w);
    alpha.push_back(a);
    beta.push_back(b);
    if (!(b > 1e-12 * std::abs(a)) || !std::isfinite(b)) break;  // invariant subspace found
    q_prev = q;
    q = w / b;
    beta_prev = b;
  }
  const int m = static_cast<int>(alpha.size());
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(m, m);
  for (int k = 0; k < m; ++k) {
    T(k, k) = alpha[k];
    if (k + 1 < m) T(k, k + 1) = T(k + 1, k) = beta[k];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(T);
  if (es.info() != Eigen::Success) throw Error("block Lanczos: the tridiagonal eigenproblem failed");
  v.setZero(n);  // the top Ritz vector: the start of a next estimate
  for (int k = 0; k < m; ++k) v += es.eigenvectors()(k, m - 1) * basis[k];
  return es.eigenvalues()(m - 1) + std::abs(beta[m - 1] * es.eigenvectors()(m - 1, m - 1));
}

}  // namespace xb::amg
