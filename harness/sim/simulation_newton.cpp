// Simulation (harness/sim/simulation_impl.hpp) under step = newton: the substep is the one Newton
// loop (newton_loop.hpp), watched through its hooks; and the reference's verdict on the run.
#include "simulation_impl.hpp"

#include <algorithm>
#include <cstdio>

namespace xb::detail {

void Simulation::newton_substep(int frame, int sub) {
  Particles& P = prob_.particles;
  NewtonHooks hooks;
  hooks.frame = frame;
  hooks.substep = sub;
  hooks.tolerance = [this](int it, double gradient) { return m_.forcing.next(it, gradient); };
  hooks.on_iterate = [&](const NewtonIterate& v) {
    where_.frame = frame;
    where_.iteration = v.iteration;
    // The authors' residual as before the loop existed: ‖C(x_{k−1}) + α̃λ_k‖ (C(x̃) at it = 0).
    if (v.iteration == 0) substep_.c_authors = v.state.C;
    const double dual = (v.state.C + alpha_tilde_.cwiseProduct(v.lambda)).norm();
    const double authors = (substep_.c_authors + alpha_tilde_.cwiseProduct(v.lambda)).norm();
    substep_.c_authors = v.state.C;
    const double h2 = h_ * h_;
    // The primal residual logged is the free gradient's h²‖∇E‖ (with contact, the active bounds' y
    // left out: the stop test's measure); the relative Newton residual is it over its value at x̃.
    if (v.iteration == 0) substep_.newton0 = std::hypot(v.gradient * h2, dual);
    substep_.energy = v.energy;
    log_entry(frame, sub, v.iteration, {dual, authors, v.gradient * h2, v.energy}, v.last);
    res_.log.relative_gradient_floor.push_back(v.gradient0 > 0 ? v.floor / v.gradient0 : 0);
    res_.log.hessian_time.push_back(v.last.hessians);
    res_.log.active_bounds.push_back(v.active);
    res_.log.inverted_elements.push_back(v.inverted);
    res_.log.smallest_twist_sum.push_back(v.twist_sum);
    if (p_.globalization == "trust_region") log_trust_region(v.iteration == 0 ? LastStep{} : v.last);
    if (v.iteration > 0) ++res_.outer_iterations;
    if (opt_.on_iteration)
      opt_.on_iteration({frame, where_.first_frame, p_.frames, sub, p_.substeps, v.iteration, p_.max_iterations,
                         v.gradient0 > 0 ? v.gradient / v.gradient0 : 0});
  };
  hooks.proceed = [this] { return !over_budget(clock_.excluded); };
  hooks.on_system = [&](const GlobalStepInput& in, int it) {
    if (!opt_.on_system) return false;
    ds_.fill(in.state, alpha_tilde_);  // capture needs A too
    substep_.b = in.b;
    if (!opt_.on_system(SystemView{frame, sub, it, ds_.A(), substep_.b, in.state, alpha_tilde_, in.x})) return false;
    stop_ = true;
    res_.message = "stopped by capture";
    return true;
  };
  hooks.phase = [this](const std::string& where) { where_.phase = where; };
  const NewtonOutcome o = m_.newton->minimise(P.x, substep_.x_pred, hooks);
  const std::string where = " at frame " + std::to_string(frame) + ", iteration " + std::to_string(o.iterations);
  switch (o.reason) {
    case StopReason::not_finite: fail("nan", "non-finite positions, energy or |grad E|" + where); break;
    case StopReason::diverged: fail("diverged", "|grad E| grew by more than 1e8 over its first value" + where); break;
    case StopReason::solver_failed:
      fail("breakdown", "linear solver " + method_ + " broke down" + where + ": " + o.message);
      break;
    case StopReason::interrupted: break;  // the budget or capture already said why
    default: end_substep(o.reason);
  }
}

void Simulation::log_trust_region(const LastStep& s) {
  IterationLog& L = res_.log;
  L.trust_region_radius.push_back(s.radius);
  L.trust_region_ratio.push_back(s.ratio);
  L.trust_region_shift.push_back(s.shift);
  L.trust_region_curvature.push_back(s.curvature);
  L.trust_region_boundary.push_back(s.boundary ? 1 : 0);
  L.trust_region_negative_curvature.push_back(s.negative_curvature ? 1 : 0);
  L.trust_region_rejections.push_back(s.rejected);
}

void Simulation::reference_verdict() {
  const auto& st = res_.log.reference_status;
  long unconverged = 0;
  for (long long ok : res_.log.reference_success) unconverged += ok ? 0 : 1;
  if (unconverged == 0) return;
  double worst = 0;
  for (double g : res_.log.reference_relative_energy_gradient) worst = std::max(worst, g);
  char text[96];
  std::snprintf(text, sizeof text, " (worst relative |grad E| %.3g)", worst);
  const std::string msg = "the reference did not converge in " + std::to_string(unconverged) + " of " +
                          std::to_string(st.size()) + " substeps" + (res_.log.reference_relative_energy_gradient.empty() ? "" : text) +
                          ": position_error is measured against an unconverged solution";
  if (res_.status == "ok") {
    res_.status = "reference_unconverged";
    res_.message = msg;
  } else {
    res_.message += res_.message.empty() ? msg : "; " + msg;
  }
}

}  // namespace xb::detail
