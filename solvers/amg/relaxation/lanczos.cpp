#include "lanczos.hpp"

#include "../../kernels.hpp"
#include "smoothers.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace xb::amg {

double lanczos_lambda_max(const SparseMatrix& A, Vector& v, int iterations, unsigned seed, const DNorm& dnorm,
                          const LanczosStep& step, const BlockOperator* blocks) {
  const long n = A.rows();
  if (v.size() != n || v.squaredNorm() == 0) {
    std::mt19937_64 rng(seed * 7919ull + 17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    v.resize(n);
    for (long i = 0; i < n; ++i) v[i] = u(rng);
  }
  const int steps = static_cast<int>(std::min<long>(n, std::max(iterations, 10)));
  Vector q = v / dnorm(v), q_prev = Vector::Zero(n), Aq(n), w(n);
  std::vector<double> alpha, beta;
  Eigen::MatrixXd basis(n, steps);  // for the top Ritz vector
  double beta_prev = 0;
  for (int k = 0; k < steps; ++k) {
    basis.col(k) = q;
    if (blocks)
      block_multiply(*blocks, A, q.data(), Aq.data(), false);
    else
      spmv(A, q, Aq);
    const double a = dot(q, Aq);  // ⟨q, D⁻¹Aq⟩_D
    step(Aq, q, q_prev, a, beta_prev, w);
    const double b = dnorm(w);
    alpha.push_back(a);
    beta.push_back(b);
    if (!(b > 1e-12 * std::abs(a)) || !std::isfinite(b)) break;  // invariant subspace found
    q_prev.swap(q);
    const double inv_b = 1.0 / b;
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) q[i] = inv_b * w[i];
    beta_prev = b;
  }
  const int m = static_cast<int>(alpha.size());
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(m, m);
  for (int k = 0; k < m; ++k) {
    T(k, k) = alpha[k];
    if (k + 1 < m) T(k, k + 1) = T(k + 1, k) = beta[k];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(T);
  if (es.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
  v.noalias() = basis.leftCols(m) * es.eigenvectors().col(m - 1);
  return es.eigenvalues()(m - 1) + std::abs(beta[m - 1] * es.eigenvectors()(m - 1, m - 1));
}

}  // namespace xb::amg
