// Simulation (harness/sim/simulation_impl.hpp): what is logged per evaluation, and the method step.
#include "simulation_impl.hpp"

#include "line_search.hpp"
#include "newton.hpp"
#include "residual_energy.hpp"

#include <cmath>

namespace xb::detail {

Simulation::Residuals Simulation::log_state(int frame, int sub, int it, const LastStep& last) {
  const Particles& P = prob_.particles;
  if (it > 0 && !local_) c_authors_ = state_.C;  // global: C(x_{k−1}), before it is re-evaluated
  evaluate_constraints(prob_, P.x, state_);
  if (it == 0) c_authors_ = state_.C;  // C(x̃); local methods keep it for the whole substep
  b_ = -(state_.C + alpha_tilde_.cwiseProduct(lambda_));
  const double dual = b_.norm();
  const double authors = (c_authors_ + alpha_tilde_.cwiseProduct(lambda_)).norm();
  primal_residual_vector(prob_, ds_, state_, P.x, x_pred_, lambda_, g_);
  const double primal = std::sqrt(particle_dot(prob_, g_, g_));
  energy_ = incremental_energy(prob_, state_, P.x, x_pred_, h_);
  if (it == 0) {
    // The scale of the relative Newton residual: ‖h²∇E(x̃)‖ = ‖Jᵀα̃⁻¹C(x̃)‖, the same for every method
    // (where every α̃ > 0; else the Newton residual at x̃, ‖C(x̃)‖).
    newton0_ = (alpha_tilde_.array() > 0).all()
                   ? energy_gradient_norm(prob_, ds_, state_, P.x, x_pred_, alpha_tilde_, h_) * h_ * h_
                   : std::hypot(primal, dual);
  }
  log_entry(frame, sub, it, {dual, authors, primal, energy_}, last);
  return {dual, authors, p_.residual_metric == "authors" ? authors : dual};
}

// One entry of the log; at it = 0 the substep's scales (r0_: the dual residual's; newton0_ is set
// by the caller).
void Simulation::log_entry(int frame, int sub, int it, const Entry& e, const LastStep& last) {
  const Particles& P = prob_.particles;
  if (it == 0) r0_ = e.dual;
  const double newton = std::hypot(e.primal, e.dual);
  IterationLog& L = res_.log;
  L.frame.push_back(frame);
  L.substep.push_back(sub);
  L.iteration.push_back(it);
  L.dual_residual.push_back(e.dual);
  L.relative_dual_residual.push_back(r0_ > 0 ? e.dual / r0_ : 0);
  L.authors_dual_residual.push_back(e.authors);
  L.authors_relative_dual_residual.push_back(r0_ > 0 ? e.authors / r0_ : 0);
  L.primal_residual.push_back(e.primal);
  L.newton_residual.push_back(newton);
  L.relative_newton_residual.push_back(newton0_ > 0 ? newton / newton0_ : 0);
  L.energy.push_back(e.energy);
  if (opt_.reference) {
    Timer err_clock;
    const double d = mass_norm_distance(prob_, P.x, x_ref_);
    // A substep whose reference does not move (x_ref = x̃) has no scale: absolute error.
    L.position_error.push_back(ref_scale_ > 0 ? d / ref_scale_ : d);
    excluded_ += err_clock.seconds();
  }
  L.wall_time.push_back(sub_clock_.seconds() - excluded_);
  log_linear(last, it);
  res_.final_dual_residual = e.dual;
  res_.relative_dual_residual = r0_ > 0 ? e.dual / r0_ : 0;
  res_.stats["final_authors_dual_residual"] = e.authors;
}

void Simulation::log_linear(const LastStep& last, int it) {
  IterationLog& L = res_.log;
  // The linear_* entries describe the step that led here (none at iteration 0).
  const LastStep none;
  const LastStep& s = it == 0 ? none : last;
  L.step_time.push_back(s.time);
  L.fill_time.push_back(s.fill);
  L.step_length.push_back(s.length);
  L.line_search_trials.push_back(s.trials);
  L.exact_hessian.push_back(s.exact ? 1 : 0);
  L.projected_elements.push_back(s.projected);
  L.linear_iterations.push_back(s.linear.iterations);
  L.linear_setup_time.push_back(s.linear.setup_time);
  L.linear_solve_time.push_back(s.linear.solve_time);
  L.linear_relative_residual.push_back(s.linear.final_relative_residual);
  L.linear_tolerance.push_back(s.tolerance);
  L.linear_setup_action.push_back(s.action);
  L.linear_history_residual.insert(L.linear_history_residual.end(), s.linear.residual_history.begin(),
                                   s.linear.residual_history.end());
  L.linear_history_time.insert(L.linear_history_time.end(), s.linear.residual_time.begin(), s.linear.residual_time.end());
  L.linear_history_offset.push_back(static_cast<long long>(L.linear_history_residual.size()));
}

Simulation::StepEnd Simulation::step(int frame, int sub, int it, double residual, LastStep& last) {
  Particles& P = prob_.particles;
  last.trials = 0;
  if (local_) {
    local_->sweep(P.x, lambda_, alpha_tilde_, state_);
    last.linear = LinearStats{};
    last.action = "";
    return StepEnd::ok;
  }
  last.tolerance = forcing_.next(it, residual);
  global_->set_tolerance(last.tolerance);
  last.linear = global_solve(frame, sub, it, last);
  if (stop_) return StepEnd::stop;
  last.action = active_->last_setup_action();
  if (last.linear.status == LinearStatus::breakdown) {
    fail("breakdown", "linear solver " + method_ + " broke down at frame " + std::to_string(frame) + ", iteration " +
                          std::to_string(it) + ": " + last.linear.message);
    return StepEnd::stop;
  }
  last.length = apply_global_step(last);
  return StepEnd::ok;
}

// Fills, sets up and solves the step.
LinearStats Simulation::global_solve(int frame, int sub, int it, LastStep& last) {
  Particles& P = prob_.particles;
  const GlobalStepInput in{state_, lambda_, P.x, g_, b_, parse_projection(p_.hessian_projection, "xpbd.hessian_projection")};
  phase_ = "the fill of the top-left block and A";
  last.fill = global_->prepare(in);
  if (opt_.on_system) {
    if (global_->form() == "primal") ds_.fill(state_, alpha_tilde_);  // capture needs A too
    if (opt_.on_system(SystemView{frame, sub, it, ds_.A(), b_, state_, alpha_tilde_, P.x})) {
      stop_ = true;
      res_.message = "stopped by capture";
      return {};
    }
  }
  const SetupKind kind = first_setup_ ? SetupKind::Structure : SetupKind::Values;
  first_setup_ = false;
  phase_ = "the setup and solve of " + method_ + (global_->form() == "primal" ? " (primal form, K's fill included)" : "");
  LinearStats st = global_->solve(in, kind, SetupContext{frame, sub, it}, dlambda_, dx_);
  if (global_->form() == "primal") last.fill = global_->primal_fill_time();
  return st;
}

double Simulation::apply_global_step(LastStep& last) {
  Particles& P = prob_.particles;
  if (p_.step == "line_search") {
    lambda_ += dlambda_;
    const double current = (state_.C + alpha_tilde_.cwiseProduct(lambda_)).norm();  // C(x) with the new λ
    const LineSearchStep ls = backtrack_dual_residual(prob_, P.x, lambda_, dx_, alpha_tilde_, current,
                                                      trial_state_, x_trial_);
    last.trials = ls.trials;
    P.x += ls.t * dx_;
    return ls.t;
  }
  lambda_ += dlambda_;
  P.x += p_.omega * dx_;
  return p_.omega;
}

}  // namespace xb::detail
