// Simulation (harness/sim/simulation_impl.hpp) under vbd and avbd: the substep is the block-descent
// loop (block_descent.hpp), watched through its hooks as newton_substep watches Newton's.
#include "simulation_impl.hpp"

#include <cmath>

namespace xb::detail {

void Simulation::block_descent_substep(int frame, int sub) {
  Particles& P = prob_.particles;
  BlockDescentHooks hooks;
  hooks.on_iterate = [&](const BlockDescentIterate& v) {
    where_.frame = frame;
    where_.iteration = v.iteration;
    // The records as Newton's: the primal residual is the free gradient's h²‖∇E‖ (with rigid
    // constraints g of AVBD's multipliers), the dual one ‖C + α̃λ‖ (0 but for rigid constraints);
    // the relative Newton residual is over its value at x̃, the scale every method shares.
    if (v.iteration == 0) substep_.newton0 = std::hypot(v.primal0, v.dual0);
    substep_.energy = v.energy;
    LastStep last;
    last.time = v.sweep_time;
    log_entry(frame, sub, v.iteration, {v.dual, v.dual, v.primal, v.energy}, last);
    res_.log.relative_gradient_floor.push_back(v.gradient0 > 0 ? v.floor / v.gradient0 : 0);
    res_.log.hessian_time.push_back(0);  // the vertex blocks are inside the sweep (step_time)
    res_.log.active_bounds.push_back(v.active);
    if (v.iteration > 0) ++res_.outer_iterations;
    if (opt_.on_iteration)
      opt_.on_iteration({frame, where_.first_frame, p_.frames, sub, p_.substeps, v.iteration, p_.max_iterations,
                         v.gradient0 > 0 ? v.gradient / v.gradient0 : 0});
  };
  hooks.proceed = [this] { return !over_budget(clock_.excluded); };
  where_.phase = "the block-descent sweeps";
  const NewtonOutcome o = m_.block->minimise(P.x, substep_.x_old, substep_.x_pred, substep_.v_old, hooks);
  const std::string where = " at frame " + std::to_string(frame) + ", iteration " + std::to_string(o.iterations);
  switch (o.reason) {
    case StopReason::not_finite: fail("nan", "non-finite positions, energy or |grad E|" + where); break;
    case StopReason::diverged: fail("diverged", "|grad E| grew by more than 1e8 over its value at x~" + where); break;
    case StopReason::interrupted: break;  // the budget already said why
    default: end_substep(o.reason);
  }
}

}  // namespace xb::detail
