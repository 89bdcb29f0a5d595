#include "lanczos.hpp"

#include "../../../core/reduce.hpp"
#include "../../kernels.hpp"
#include "../block_kernels.hpp"

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

double estimate_lambda_max(const SparseMatrix& A, const Vector& inv_diag, Vector& v, int iterations, unsigned seed) {
  // Lanczos on D⁻¹A in the D inner product (D⁻¹A is self-adjoint there). Power iteration
  // approaches λ_max from below too slowly on tet ARAP systems: an estimate 15% low makes the
  // degree-3 Chebyshev polynomial on [λ/30, 1.1λ] amplify the top modes and the V-cycle
  // indefinite (CG then breaks down with r'z <= 0). The largest Ritz value plus its residual
  // |β_k y_k| bounds an eigenvalue from above; it is capped by Gershgorin's bound on D⁻¹A,
  // which is a true upper bound.
  const long n = A.rows();
  if (n == 0) return 0;
  const int* outer = A.outerIndexPtr();
  const double* val = A.valuePtr();
  double gershgorin = 0;
#pragma omp parallel for schedule(static) reduction(max : gershgorin) if (n > kMinParallelRows)
  for (long i = 0; i < n; ++i) {
    double row = 0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) row += std::abs(val[k]);
    gershgorin = std::max(gershgorin, inv_diag[i] * row);
  }
  auto dnorm = [&](const Vector& x) {
    return std::sqrt(deterministic_sum(n, [&](long i) { return inv_diag[i] > 0 ? x[i] * x[i] / inv_diag[i] : 0.0; }));
  };
  auto step = [&](const Vector& Aq, const Vector& q, const Vector& q_prev, double a, double beta, Vector& w) {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) w[i] = inv_diag[i] * Aq[i] - a * q[i] - beta * q_prev[i];
  };
  const double bound = lanczos_lambda_max(A, v, iterations, seed, dnorm, step);
  return std::isnan(bound) ? gershgorin : std::min(bound, gershgorin);
}

}  // namespace xb::amg
