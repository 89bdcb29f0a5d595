#include "newton_loop.hpp"

#include "newton.hpp"
#include "residual_energy.hpp"

#include "../../solvers/timer.hpp"

#include <cmath>
#include <utility>

namespace xb {

NewtonSettings NewtonSettings::from(const Params& p) {
  NewtonSettings s;
  s.stop.rtol = p.rtol;
  s.stop.atol = p.atol;
  s.stop.max_iterations = p.max_iterations;
  s.projection = parse_projection_strategy(p.hessian_projection);
  s.exact_below = p.exact_hessian_below;
  s.line_search = parse_line_search(p.line_search);
  s.globalization = parse_globalization(p.globalization, "xpbd.globalization");
  s.subproblem = parse_trust_region_subproblem(p.trust_region_subproblem, "xpbd.trust_region_subproblem");
  s.linear_max_iterations = p.linear.max_iterations;
  SolverSettings direct = p;
  direct.cholmod.refactor = "always";
  s.make_direct = [direct] { return make_linear_solver("cholmod", direct); };
  return s;
}

NewtonLoop::NewtonLoop(const Problem& prob, const DualSystem& ds, GlobalStep& step, const Eigen::VectorXd& alpha_tilde,
                       double h, const NewtonSettings& s)
    : prob_(prob), ds_(ds), step_(step), alpha_tilde_(alpha_tilde), h_(h), s_(s),
      strategy_(prob, s.projection, s.exact_below), bounds_(prob),
      search_(prob, ds, alpha_tilde, h, s.line_search, &bounds_,
              [this](const Eigen::Matrix3Xd& x, ConstraintState& st) { evaluate_at(x, st); }) {
  if (s.globalization == Globalization::trust_region) make_trust_region();
}

// Through the element Hessians where there are (the step's `full`): their SVDs are kept for the
// Hessian fill at the same point, one decomposition per element per iteration.
void NewtonLoop::evaluate_at(const Eigen::Matrix3Xd& x, ConstraintState& state) {
  if (ElementHessians* eh = step_.elements())
    eh->evaluate(x, state);
  else
    evaluate_constraints(prob_, x, state, newton_rest_epsilon);
}

void NewtonLoop::evaluate(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  evaluate_at(x, state_);
  eliminate_multipliers(state_, alpha_tilde_, lambda_);
  primal_residual_vector(prob_, ds_, state_, x, x_pred, lambda_, g_);
  energy_ = incremental_energy(prob_, state_, x, x_pred, h_);
}

bool NewtonLoop::direction(int it, double relative, const Eigen::Matrix3Xd& x, StepRecord& rec,
                           const NewtonHooks& hooks, NewtonOutcome& out) {
  ElementProjection proj = strategy_.first(it, relative);
  for (;;) {
    const GlobalStepInput in{state_, lambda_, x, g_, b_, proj.base, &proj, &held_, step_.elements() != nullptr};
    if (hooks.phase) hooks.phase("the fill of the element Hessians");
    rec.hessians += step_.prepare(in);
    if (hooks.on_system && hooks.on_system(in, it)) {
      out.reason = StopReason::interrupted;
      return false;
    }
    const SetupKind kind = first_setup_ ? SetupKind::Structure : SetupKind::Values;
    first_setup_ = false;
    if (hooks.phase) hooks.phase("the setup and solve of the Newton step");
    const LinearStats st = step_.solve(in, kind, SetupContext{hooks.frame, hooks.substep, it}, dlambda_, dx_);
    rec.fill += step_.primal_fill_time();
    rec.linear = st;
    rec.action = step_.solver().last_setup_action();
    ++rec.solves;
    const ElementHessians* eh = step_.elements();
    rec.indefinite = eh ? eh->indefinite_elements() : 0;
    rec.projected = eh ? eh->projected_elements() : 0;
    rec.exact = ProjectionStrategy::exact(proj);
    // The descent safeguard: only a finite descent direction goes on to the line search.
    const bool broke = st.status == LinearStatus::breakdown || !dx_.allFinite();
    if (!broke && particle_dot(prob_, g_, dx_) < 0) return true;
    ElementProjection more;
    if (!eh || !strategy_.next(proj, more)) {
      out.reason = StopReason::solver_failed;
      out.message = broke ? "the linear solve broke down on the projected Hessian: " + st.message
                          : "the projected Hessian's step is not a descent direction (grad E . dx >= 0)";
      return false;
    }
    proj = more;
  }
}

NewtonOutcome NewtonLoop::minimise(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const NewtonHooks& hooks,
                                   const Eigen::Matrix3Xd* start) {
  NewtonOutcome out;
  const double h2 = h_ * h_;
  x = start ? *start : x_pred;
  bounds_.project(x);
  strategy_.begin_substep();
  if (tr_) begin_trust_region();
  if (hooks.phase) hooks.phase("the constraint evaluation");
  evaluate(x, x_pred);
  StepRecord rec;
  for (int it = 0;; ++it) {
    b_ = -(state_.C + alpha_tilde_.cwiseProduct(lambda_));
    bounds_.active_set(x, g_, active_);
    free_g_ = g_;
    PlaneBounds::free_gradient(active_, free_g_);
    const double gn = std::sqrt(particle_dot(prob_, free_g_, free_g_)) / h2;
    if (it == 0) out.gradient0 = gn;
    out.gradient = gn;
    out.floor = gradient_rounding_floor(prob_, ds_, state_, x, alpha_tilde_) / h2;
    out.iterations = it;
    double twist_sum = INFINITY;
    const int inverted = step_.elements() ? step_.elements()->inverted_tets(twist_sum) : 0;
    const NewtonIterate view{it, x, state_, lambda_, g_, gn, out.gradient0, out.floor, energy_,
                             static_cast<int>(active_.size()), inverted, twist_sum, rec};
    if (hooks.on_iterate) hooks.on_iterate(view);
    out.reason = s_.stop.test(it, gn, out.gradient0, out.floor, std::isfinite(energy_) && x.allFinite());
    if (out.reason == StopReason::running && hooks.proceed && !hooks.proceed()) out.reason = StopReason::interrupted;
    // The trust region looks past a solved gradient below the iteration limit: a saddle goes on.
    const bool solved = stop_reason_success(out.reason);
    if (out.reason != StopReason::running && !(solved && tr_ && it < s_.stop.max_iterations)) return out;

    Timer clock;
    rec = StepRecord{};
    rec.tolerance = hooks.tolerance ? hooks.tolerance(it, gn) : 0;
    if (hooks.tolerance) step_.set_tolerance(rec.tolerance);
    bounds_.active_set(x, g_, held_, bounds_.epsilon(x, g_));  // the step holds the ε-active set
    if (tr_) {  // the trust region's models; a gradient at its tolerance with negative curvature is a saddle
      if (!trust_region_models(it, x, rec, hooks, out)) return out;
      if (solved && !trust_region_saddle()) return out;
      out.reason = StopReason::running;
    }
    const bool moved = tr_ ? trust_region_step(it, x, x_pred, rec, hooks, out)
                           : line_search_step(it, gn, x, x_pred, rec, hooks, out);
    if (!moved) return out;
    rec.time = clock.seconds();
  }
}

bool NewtonLoop::line_search_step(int it, double gradient, Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                                  StepRecord& rec, const NewtonHooks& hooks, NewtonOutcome& out) {
  const double h2 = h_ * h_;
  if (!direction(it, out.gradient0 > 0 ? gradient / out.gradient0 : 0, x, rec, hooks, out)) return false;
  if (hooks.phase) hooks.phase("the line search on E");
  const double rounding = energy_rounding(prob_, state_, x, x_pred, h_, energy_);
  const EnergySearch s = search_.search({x, dx_, g_, energy_, rounding}, x_pred, trial_);
  rec.trials = s.trials;
  if (!s.accepted) {
    out.reason = StopCriterion::failed_search(gradient, out.floor);
    return false;
  }
  // The quadratic model the step solved, at the step s = x(t) − x taken: its decrease
  // −(gᵀs + ½sᵀKs)/h², K the (projected) Hessian of the last solve — exact or not.
  step_taken_ = trial_.x - x;
  rec.actual = energy_ - s.energy;
  rec.predicted = -(particle_dot(prob_, g_, step_taken_) + 0.5 * step_.curvature(step_taken_)) / h2;
  strategy_.after_step(rec.actual, rec.predicted);
  rec.length = s.t;
  accept_trial(x, s.energy);
  return true;
}

void NewtonLoop::accept_trial(Eigen::Matrix3Xd& x, double energy) {
  std::swap(x, trial_.x);
  std::swap(state_, trial_.state);
  std::swap(lambda_, trial_.lambda);
  std::swap(g_, trial_.g);
  energy_ = energy;
}

}  // namespace xb
