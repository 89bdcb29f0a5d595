// The authors' global step rule (`step = line_search`): backtracking on the dual residual.
// From the linear step (Δλ, Δx = M⁻¹∇CᵀΔλ) it tries t = 1, 1/2, 1/4, … and takes the first t with
//   ‖C(x + tΔx) + α̃(λ + tΔλ)‖ < current   (the dual residual at x, λ before the step).
// After `line_search_max_halvings` halvings without a decrease it takes the trial with the smallest
// residual (never a zero step: the outer loop then shows the stall instead of standing still).
// Colliders are not applied to trials (the stepper projects after the step, as for `fixed`).
#pragma once

#include "../../problems/problem.hpp"

namespace xb {

constexpr int line_search_max_halvings = 10;  // smallest trial t = 2^-10

struct LineSearchStep {
  double t = 1;            // the step length taken
  double residual = 0;     // ‖C(x + tΔx) + α̃(λ + tΔλ)‖ at that t
  int trials = 0;          // constraint evaluations spent
  bool decreased = false;  // false: no trial went below `current` (the best one was taken)
};

// Chooses t; does not change x or λ. `scratch` and `x_trial` are work space.
LineSearchStep backtrack_dual_residual(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda,
                                       const Eigen::Matrix3Xd& dx, const Eigen::VectorXd& dlambda,
                                       const Eigen::VectorXd& alpha_tilde, double current, ConstraintState& scratch,
                                       Eigen::Matrix3Xd& x_trial);

}  // namespace xb
