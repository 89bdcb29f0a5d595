// The authors' global step rule (`step = line_search`), as their release code runs it: λ takes the
// full Δλ first; then, with that λ on both sides, x + tΔx is tried for t = 1, 1/2, 1/4, … and the
// first t with
//   ‖C(x + tΔx) + α̃λ‖ < ‖C(x) + α̃λ‖
// is taken. Once t falls below `line_search_min_step` without a decrease, x stays (t = 0; λ has
// still moved, so the outer loop does not stand still).
// Colliders are not applied to trials (the stepper projects after the step, as for `fixed`).
#pragma once

#include "../../problems/problem.hpp"

namespace xb {

constexpr double line_search_min_step = 1e-9;  // the authors' EPSILON: 31 trials at most

struct LineSearchStep {
  double t = 1;            // the step length taken (0: no trial decreased the objective)
  double residual = 0;     // ‖C(x + tΔx) + α̃λ‖ at the last trial
  int trials = 0;          // constraint evaluations spent
  bool decreased = false;  // false: t = 0
};

// Chooses t for x; `lambda` is already λ + Δλ; `current` = ‖C(x) + α̃λ‖ with that λ. Does not
// change x. `scratch` and `x_trial` are work space.
LineSearchStep backtrack_dual_residual(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda,
                                       const Eigen::Matrix3Xd& dx, const Eigen::VectorXd& alpha_tilde, double current,
                                       ConstraintState& scratch, Eigen::Matrix3Xd& x_trial);

}  // namespace xb
