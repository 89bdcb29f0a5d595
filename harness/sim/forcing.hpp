// The inner tolerance of each outer iteration (linear.forcing): how accurately the linear step
// is solved, from the outer (dual) residual's progress. A Newton-like outer loop gains nothing
// from a linear solve far more accurate than the outer residual's next reduction.
//   fixed:            η_k = linear.tol.
//   eisenstat_walker: choice 2 of Eisenstat & Walker (1996), "Choosing the forcing terms in an
//                     inexact Newton method": η_0 = η_max and, for k ≥ 1,
//                       η_k = γ (‖r_k‖ / ‖r_{k−1}‖)^α,
//                     safeguarded by η_k = max(η_k, γ η_{k−1}^α) when γ η_{k−1}^α > 0.1, then
//                     capped by η_max = linear.forcing_max and floored by linear.tol.
// r_k is the dual residual ‖C + α̃λ‖ the stepper evaluates before step k; the sequence starts
// again every substep.
#pragma once

#include "../../solvers/solver_settings.hpp"

namespace xb {

class ForcingRule {
 public:
  explicit ForcingRule(const LinearSettings& s);
  // The tolerance of step k, given the outer residual before it; k = 0 starts a new sequence.
  double next(int k, double residual);

 private:
  const LinearSettings s_;
  const bool fixed_;
  double previous_residual_ = 0, previous_eta_ = 0;
};

}  // namespace xb
