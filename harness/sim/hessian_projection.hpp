// The projection strategy of Newton on E (xpbd.hessian_projection; docs/newton.md): which element
// Hessians H_j enter K = M + Σ_j π(H_j) projected, iteration by iteration, and what to try when the
// solve fails (breaks down on an indefinite K, or gives no descent direction). The loop
// (newton_loop.hpp) asks first() for an iteration's first try, next() after a failed one, and
// tells after_step() how well the quadratic model predicted the decrease.
//  clamp, abs      every element, every iteration (Projected Newton)
//  adaptive        clamp until ‖∇E‖ < xpbd.exact_hessian_below of its first value, then exact
//  on_demand       exact every iteration; clamped only for a try that failed (Longva et al. 2023)
//  progressive     the clamp only for the elements whose smallest eigenvalue is below −τ of their
//                  own stiffness (ψ < −τ for a tet: the nearly flat or inverted ones), the others
//                  exact; τ = 1 at each substep's start, 0.1 after a failed try (0 after
//                  0.1: every element clamped), a decade higher after a step whose decrease of E
//                  was ≥ 3/4 of the quadratic model's, up to 1e3 (exact everywhere) (after
//                  Fernández-Fernández et al. 2026, who select the projected elements by their
//                  local residual; here by the eigenvalue, which at bunny:270k singles out the
//                  ~0.5% of the elements that make K indefinite)
//  trust_region    clamp while the model's prediction held at the last step (ρ = actual/predicted
//                  decrease ≥ 1/4), abs where it did not (Chen et al. 2024)
// Every strategy ends at the clamp of every element before giving up (the clamp is PSD).
#pragma once

#include "../stepper_settings.hpp"
#include "../../problems/element_hessians.hpp"
#include "../../problems/problem.hpp"

#include <string>

namespace xb {

class ProjectionStrategy {
 public:
  // Throws xb::Error for an unknown name.
  ProjectionStrategy(const Problem& prob, const std::string& name, double exact_below);
  const std::string& name() const { return name_; }
  void begin_substep();
  // The first try of iteration `it`; relative_gradient = ‖∇E‖ over its first value.
  ElementProjection first(int it, double relative_gradient);
  // After a failed try with `tried`: the next one, or false when every element was clamped.
  bool next(const ElementProjection& tried, ElementProjection& out);
  // After an accepted step: the decrease of E and the one the quadratic model predicted.
  void after_step(double actual, double predicted);
  // Whether `p` leaves some element exact.
  static bool exact(const ElementProjection& p) { return p.base == Projection::none || p.tolerance > 0; }

 private:
  const Problem& prob_;
  std::string name_;
  double exact_below_;
  bool model_held_ = true;          // trust_region
  static constexpr double max_tau = 1e3;  // progressive: τ at which every element is exact
  double tau_ = 1;                  // progressive: the tolerated negative curvature
};

}  // namespace xb
