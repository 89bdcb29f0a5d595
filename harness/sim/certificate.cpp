#include "certificate.hpp"

#include "newton.hpp"
#include <algorithm>

#include "../../core/reduce.hpp"

namespace xb {

double error_bound_factor(double q, bool at_floor) {
  const double contraction = q < 1 ? 1 / (1 - q) : INFINITY;  // NaN compares false: ∞
  return at_floor ? std::min(2.0, contraction) : contraction;
}

MinimiserCertificate::MinimiserCertificate(const Problem& prob, const DualSystem& ds, GlobalStep& step,
                                           const Eigen::VectorXd& alpha_tilde, double h)
    : prob_(prob), ds_(ds), step_(step), alpha_tilde_(alpha_tilde), h_(h), bounds_(prob) {}

double MinimiserCertificate::mass_norm(const Vector& v) const {
  const std::vector<int>& free = step_.primal()->system().free_particles();
  const Eigen::VectorXd& w = prob_.particles.w;
  return std::sqrt(deterministic_sum(static_cast<long>(free.size()),
                                     [&](long i) { return v.segment<3>(3 * i).squaredNorm() / w[free[i]]; }));
}

double MinimiserCertificate::step_norm(const Eigen::Matrix3Xd& v, Vector& out) {
  Eigen::Matrix3Xd held = v;
  PlaneBounds::free_gradient(active_, held);  // the held y carry no step
  const std::vector<int>& free = step_.primal()->system().free_particles();
  v_dof_.resize(3 * static_cast<long>(free.size()));
  for (size_t i = 0; i < free.size(); ++i) v_dof_.segment<3>(3 * static_cast<long>(i)) = held.col(free[i]);
  if (!factor_.solve(v_dof_, out) || !out.allFinite()) return NAN;
  return mass_norm(out);
}

void MinimiserCertificate::gradient_at(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  eliminate_multipliers(state_, alpha_tilde_, lambda_);
  primal_residual_vector(prob_, ds_, state_, x, x_pred, lambda_, g_);
}

Certificate MinimiserCertificate::certify(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  Certificate c;
  const double h2 = h_ * h_;
  ElementHessians* eh = step_.elements();
  if (eh)
    eh->evaluate(x, state_);
  else
    evaluate_constraints(prob_, x, state_, newton_rest_epsilon);
  gradient_at(x, x_pred);
  b_ = -(state_.C + alpha_tilde_.cwiseProduct(lambda_));
  bounds_.active_set(x, g_, active_);
  c.floor = gradient_rounding_floor(prob_, ds_, state_, x, alpha_tilde_) / h2;
  gradient_rounding_sample(prob_, ds_, state_, x, alpha_tilde_, n_);
  {
    Eigen::Matrix3Xd free_g = g_;
    PlaneBounds::free_gradient(active_, free_g);
    c.gradient = std::sqrt(particle_dot(prob_, free_g, free_g)) / h2;
  }
  const ElementProjection exact{Projection::none, 0};
  const GlobalStepInput in{state_, lambda_, x, g_, b_, Projection::none, &exact, &active_, eh != nullptr};
  const SparseMatrix& K = step_.fill_newton_system(in, g_dof_);
  std::string why;
  if (!factor_.factorise(K, why)) {
    factor_.release();
    c.note = "the exact Hessian on the free set is " + why;
    return c;
  }
  c.positive_definite = true;
  c.newton_step = step_norm(g_, s_);
  const std::vector<int>& free = step_.primal()->system().free_particles();
  x_plus_ = x;
  for (size_t i = 0; i < free.size(); ++i) x_plus_.col(free[i]) -= s_.segment<3>(3 * static_cast<long>(i));
  c.rounding_step = step_norm(n_, s_);
  evaluate_constraints(prob_, x_plus_, state_, newton_rest_epsilon);
  gradient_at(x_plus_, x_pred);
  const double chord = step_norm(g_, s_);
  factor_.release();  // a second factor of K beside the reference's own is not kept between substeps
  if (std::isnan(c.newton_step) || std::isnan(c.rounding_step) || std::isnan(chord)) {
    c.note = "CHOLMOD's solve with the exact Hessian failed";
    return c;
  }
  c.contraction = c.newton_step > 0 ? chord / c.newton_step : 0;
  c.error_bound = error_bound_factor(c.contraction, c.gradient <= c.floor) * (c.newton_step + c.rounding_step);
  if (!std::isfinite(c.error_bound))
    c.note = "the chord step from the reference did not contract (q = " + std::to_string(c.contraction) +
             ") with |grad E| above its rounding floor";
  return c;
}

}  // namespace xb
