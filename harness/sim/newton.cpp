#include "newton.hpp"

#include "residual_energy.hpp"

#include "../../core/reduce.hpp"

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

EnergySearch armijo_on_energy(const Problem& prob, const DualSystem& ds, const Eigen::Matrix3Xd& x,
                              const Eigen::Matrix3Xd& dx, const Eigen::Matrix3Xd& x_pred,
                              const Eigen::VectorXd& alpha_tilde, double h, double energy, double slope,
                              double grad_norm, ConstraintState& scratch, Eigen::Matrix3Xd& x_trial) {
  EnergySearch s;
  s.energy = energy;
  if (!(slope < 0)) return s;  // not a descent direction (or NaN): no step can pass the test
  const double rounding = energy_rounding_factor * std::numeric_limits<double>::epsilon() * std::abs(energy);
  for (double t = 1; t >= energy_search_min_step; t *= 0.5) {
    x_trial = x + t * dx;
    evaluate_constraints(prob, x_trial, scratch);
    ++s.trials;
    const double e = incremental_energy(prob, scratch, x_trial, x_pred, h);
    s.on_gradient = -t * slope <= rounding;
    // A NaN trial (a degenerate element) never passes either test.
    // In the rounding regime E may not rise by more than its rounding either.
    const bool pass = s.on_gradient
                          ? e <= energy + rounding && energy_gradient_norm(prob, ds, scratch, x_trial, x_pred,
                                                                           alpha_tilde, h) <= (1 - armijo_c * t) * grad_norm
                          : e <= energy + armijo_c * t * slope;
    if (pass) {
      s.t = t;
      s.accepted = true;
      s.energy = e;
      return s;
    }
  }
  return s;
}

}  // namespace xb
