#include "energy_line_search.hpp"

#include "newton.hpp"
#include "residual_energy.hpp"

#include "../../core/error.hpp"

#include <cmath>
#include <utility>

namespace xb {

LineSearchKind parse_line_search(const std::string& name) {
  if (name == "armijo") return LineSearchKind::armijo;
  if (name == "robust_armijo") return LineSearchKind::robust_armijo;
  throw Error("xpbd.line_search: unknown line search '" + name + "' (valid: robust_armijo, armijo)");
}

EnergyLineSearch::EnergyLineSearch(const Problem& prob, const DualSystem& ds, const Eigen::VectorXd& alpha_tilde,
                                   double h, LineSearchKind kind, const PlaneBounds* bounds, ConstraintEvaluator evaluate)
    : prob_(prob), ds_(ds), alpha_tilde_(alpha_tilde), h_(h), kind_(kind),
      bounds_(bounds && !bounds->empty() ? bounds : nullptr), evaluate_(std::move(evaluate)) {
  if (!evaluate_)
    evaluate_ = [this](const Eigen::Matrix3Xd& x, ConstraintState& s) { evaluate_constraints(prob_, x, s, newton_rest_epsilon); };
}

EnergySearch EnergyLineSearch::search(const LineSearchStart& start, const Eigen::Matrix3Xd& x_pred,
                                      LineSearchTrial& trial) const {
  EnergySearch s;
  s.energy = start.energy;
  const double h2 = h_ * h_;
  if (!(particle_dot(prob_, start.g, start.dx) < 0)) return s;  // not a descent direction (or NaN)
  const double rounding = 2 * start.energy_rounding;  // of E(x(t)) − E(x): both E's
  Eigen::Matrix3Xd step;
  for (double t = 1; t >= energy_search_min_step; t *= 0.5) {
    trial.x = start.x + t * start.dx;
    if (bounds_) bounds_->project(trial.x);
    step = trial.x - start.x;
    const double slope = particle_dot(prob_, start.g, step) / h2;  // Δ(t) along the projected path
    evaluate_(trial.x, trial.state);
    ++s.trials;
    const double e = incremental_energy(prob_, trial.state, trial.x, x_pred, h_);
    // A NaN trial (a degenerate element) passes neither test.
    bool pass = slope < 0 && e <= start.energy + armijo_c * slope;
    bool on_gradient = false;
    if (!pass && kind_ == LineSearchKind::robust_armijo && slope < 0 && std::abs(e - start.energy) <= rounding) {
      eliminate_multipliers(trial.state, alpha_tilde_, trial.lambda);
      primal_residual_vector(prob_, ds_, trial.state, trial.x, x_pred, trial.lambda, trial.g);
      const double trapezoid = 0.5 * (particle_dot(prob_, start.g, step) + particle_dot(prob_, trial.g, step)) / h2;
      pass = on_gradient = trapezoid <= armijo_c * slope;
    }
    if (pass) {
      if (!on_gradient) {
        eliminate_multipliers(trial.state, alpha_tilde_, trial.lambda);
        primal_residual_vector(prob_, ds_, trial.state, trial.x, x_pred, trial.lambda, trial.g);
      }
      s.t = t;
      s.accepted = true;
      s.on_gradient = on_gradient;
      s.energy = e;
      return s;
    }
  }
  return s;
}

}  // namespace xb
