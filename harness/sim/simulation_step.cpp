// Simulation (harness/sim/simulation_impl.hpp): what is logged per evaluation, and the method step.
#include "simulation_impl.hpp"

#include "line_search.hpp"
#include "newton.hpp"
#include "residual_energy.hpp"

#include <cmath>

namespace xb::detail {

Simulation::Residuals Simulation::log_state(int frame, int sub, int it, const LastStep& last) {
  const Particles& P = prob_.particles;
  if (it > 0 && !m_.local) substep_.c_authors = substep_.state.C;  // global: C(x_{k−1}), before it is re-evaluated
  evaluate_constraints(prob_, P.x, substep_.state);
  if (it == 0) substep_.c_authors = substep_.state.C;  // C(x̃); local methods keep it for the whole substep
  substep_.b = -(substep_.state.C + alpha_tilde_.cwiseProduct(substep_.lambda));
  const double dual = substep_.b.norm();
  const double authors = (substep_.c_authors + alpha_tilde_.cwiseProduct(substep_.lambda)).norm();
  primal_residual_vector(prob_, ds_, substep_.state, P.x, substep_.x_pred, substep_.lambda, substep_.g);
  const double primal = std::sqrt(particle_dot(prob_, substep_.g, substep_.g));
  substep_.energy = incremental_energy(prob_, substep_.state, P.x, substep_.x_pred, h_);
  if (it == 0) {
    // The scale of the relative Newton residual: ‖h²∇E(x̃)‖ = ‖Jᵀα̃⁻¹C(x̃)‖, the same for every method
    // (where every α̃ > 0; else the Newton residual at x̃, ‖C(x̃)‖).
    substep_.newton0 = (alpha_tilde_.array() > 0).all()
                   ? energy_gradient_norm(prob_, ds_, substep_.state, P.x, substep_.x_pred, alpha_tilde_, h_) * h_ * h_
                   : std::hypot(primal, dual);
  }
  log_entry(frame, sub, it, {dual, authors, primal, substep_.energy}, last);
  return {dual, authors, p_.residual_metric == "authors" ? authors : dual};
}

// One entry of the log; at it = 0 the substep's scales (r0_: the dual residual's; newton0_ is set
// by the caller).
void Simulation::log_entry(int frame, int sub, int it, const Entry& e, const LastStep& last) {
  const Particles& P = prob_.particles;
  if (it == 0) substep_.r0 = e.dual;
  const double newton = std::hypot(e.primal, e.dual);
  IterationLog& L = res_.log;
  L.frame.push_back(frame);
  L.substep.push_back(sub);
  L.iteration.push_back(it);
  L.dual_residual.push_back(e.dual);
  L.relative_dual_residual.push_back(substep_.r0 > 0 ? e.dual / substep_.r0 : 0);
  L.authors_dual_residual.push_back(e.authors);
  L.authors_relative_dual_residual.push_back(substep_.r0 > 0 ? e.authors / substep_.r0 : 0);
  L.primal_residual.push_back(e.primal);
  L.newton_residual.push_back(newton);
  L.relative_newton_residual.push_back(substep_.newton0 > 0 ? newton / substep_.newton0 : 0);
  L.energy.push_back(e.energy);
  if (opt_.reference) {
    Timer err_clock;
    const double d = mass_norm_distance(prob_, P.x, truth_.x);
    // The scale is positive but where no particle is free (ReferenceSolution::error_scale).
    L.position_error.push_back(truth_.scale > 0 ? d / truth_.scale : d);
    clock_.excluded += err_clock.seconds();
  }
  L.wall_time.push_back(clock_.sub.seconds() - clock_.excluded);
  log_linear(last, it);
  res_.final_dual_residual = e.dual;
  res_.relative_dual_residual = substep_.r0 > 0 ? e.dual / substep_.r0 : 0;
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
  if (m_.local) {
    m_.local->sweep(P.x, substep_.lambda, alpha_tilde_, substep_.state);
    last.linear = LinearStats{};
    last.action = "";
    return StepEnd::ok;
  }
  last.tolerance = m_.forcing.next(it, residual);
  m_.global->set_tolerance(last.tolerance);
  last.linear = global_solve(frame, sub, it, last);
  if (stop_) return StepEnd::stop;
  last.action = m_.active->last_setup_action();
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
  const GlobalStepInput in{substep_.state, substep_.lambda, P.x, substep_.g, substep_.b, m_.projection};
  where_.phase = "the fill of the top-left block and A";
  last.fill = m_.global->prepare(in);
  if (opt_.on_system) {
    if (m_.global->form() == "primal") ds_.fill(substep_.state, alpha_tilde_);  // capture needs A too
    if (opt_.on_system(SystemView{frame, sub, it, ds_.A(), substep_.b, substep_.state, alpha_tilde_, P.x})) {
      stop_ = true;
      res_.message = "stopped by capture";
      return {};
    }
  }
  const SetupKind kind = m_.first_setup ? SetupKind::Structure : SetupKind::Values;
  m_.first_setup = false;
  where_.phase = "the setup and solve of " + method_ + (m_.global->form() == "primal" ? " (primal form, K's fill included)" : "");
  LinearStats st = m_.global->solve(in, kind, SetupContext{frame, sub, it}, substep_.dlambda, substep_.dx);
  if (m_.global->form() == "primal") last.fill = m_.global->primal_fill_time();
  return st;
}

double Simulation::apply_global_step(LastStep& last) {
  Particles& P = prob_.particles;
  if (p_.step == "line_search") {
    substep_.lambda += substep_.dlambda;
    const double current = (substep_.state.C + alpha_tilde_.cwiseProduct(substep_.lambda)).norm();  // C(x) with the new λ
    const LineSearchStep ls = backtrack_dual_residual(prob_, P.x, substep_.lambda, substep_.dx, alpha_tilde_, current,
                                                      substep_.trial_state, substep_.x_trial);
    last.trials = ls.trials;
    P.x += ls.t * substep_.dx;
    return ls.t;
  }
  substep_.lambda += substep_.dlambda;
  P.x += p_.omega * substep_.dx;
  return p_.omega;
}

}  // namespace xb::detail
