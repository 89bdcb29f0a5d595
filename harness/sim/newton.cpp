#include "newton.hpp"

#include "../../core/reduce.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace xb {

void primal_residual_vector(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& lambda,
                            Eigen::Matrix3Xd& g) {
  ds.apply_gradT(s, lambda, g);
  const Eigen::VectorXd& w = prob.particles.w;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    g.col(p) = w[p] > 0 ? Eigen::Vector3d((x.col(p) - x_pred.col(p)) / w[p] - g.col(p)) : Eigen::Vector3d::Zero();
}

void eliminate_multipliers(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, Eigen::VectorXd& lambda) {
  lambda = -s.C.cwiseQuotient(alpha_tilde);
}

double particle_dot(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  const Eigen::VectorXd& w = prob.particles.w;
  return deterministic_sum(a.cols(), [&](long p) { return w[p] > 0 ? a.col(p).dot(b.col(p)) : 0.0; });
}

double energy_gradient_norm(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                            const Eigen::VectorXd& alpha_tilde, double h) {
  Eigen::VectorXd lambda;
  eliminate_multipliers(s, alpha_tilde, lambda);
  Eigen::Matrix3Xd g;
  primal_residual_vector(prob, ds, s, x, x_pred, lambda, g);
  return std::sqrt(particle_dot(prob, g, g)) / (h * h);
}

namespace {
// X_j‖∇C_j‖: constraint j's rounding ε·X_j‖∇C_j‖ over ε (X_j the largest |x| of its particles).
double constraint_rounding(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x, int j) {
  double size = 0, grad = 0;
  const auto ps = prob.constraint_particles(j);
  for (int a = 0; a < 4; ++a)
    if (ps[a] >= 0) {
      size = std::max(size, x.col(ps[a]).cwiseAbs().maxCoeff());
      grad += s.grad[j][a].squaredNorm();
    }
  return size * std::sqrt(grad);
}
}  // namespace

namespace {
// ±1 by a hash of k: the sign of sample entry k.
double hashed_sign(unsigned long long k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return (k & 1) ? 1.0 : -1.0;
}
}  // namespace

void gradient_rounding_sample(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                              const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, Eigen::Matrix3Xd& n) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const int m = prob.num_constraints();
  Eigen::VectorXd y(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) y[j] = hashed_sign(j) * eps * constraint_rounding(prob, s, x, j) / alpha_tilde[j];
  ds.apply_gradT(s, y, n);
  const Eigen::VectorXd& w = prob.particles.w;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(n.cols()); ++p) {
    if (!(w[p] > 0)) {
      n.col(p).setZero();
      continue;
    }
    const double inertia = eps * x.col(p).cwiseAbs().maxCoeff() / w[p];
    for (int d = 0; d < 3; ++d) n(d, p) += hashed_sign((static_cast<unsigned long long>(m) + 3ULL * p + d)) * inertia;
  }
}

double gradient_rounding_floor(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                               const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde) {
  const int m = prob.num_constraints();
  Eigen::VectorXd y(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) y[j] = constraint_rounding(prob, s, x, j) / alpha_tilde[j];
  Eigen::Matrix3Xd f;
  ds.apply_abs_gradT(s, y, f);
  const Eigen::VectorXd& w = prob.particles.w;
  const double sum = deterministic_sum(f.cols(), [&](long p) {
    if (!(w[p] > 0)) return 0.0;
    return (f.col(p) + Eigen::Vector3d::Constant(x.col(p).cwiseAbs().maxCoeff() / w[p])).squaredNorm();
  });
  return std::numeric_limits<double>::epsilon() * std::sqrt(sum);
}

double energy_rounding(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& x_pred, double h, double energy) {
  const Eigen::VectorXd& w = prob.particles.w;
  const double inertia = deterministic_sum(x.cols(), [&](long p) {
    if (!(w[p] > 0)) return 0.0;
    const double r = (x.col(p) - x_pred.col(p)).norm() *
                     (x.col(p).cwiseAbs().maxCoeff() + x_pred.col(p).cwiseAbs().maxCoeff()) / (w[p] * h * h);
    return r * r;
  });
  const double potential = deterministic_sum(prob.num_constraints(), [&](long j) {
    const double a = prob.compliance(static_cast<int>(j));
    if (!(a > 0)) return 0.0;
    const double r = std::abs(s.C[j]) * constraint_rounding(prob, s, x, static_cast<int>(j)) / a;
    return r * r;
  });
  return std::numeric_limits<double>::epsilon() * (std::abs(energy) + std::sqrt(inertia + potential));
}

}  // namespace xb
