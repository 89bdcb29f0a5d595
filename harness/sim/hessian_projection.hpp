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
//  rho_switch      clamp while the quadratic model predicted the last step's decrease of E (ρ =
//                  actual/predicted ≥ 1/4), abs where it did not (Chen et al. 2024's ρ-driven switch
//                  between the two filters: no radius, no rejected step — not a trust region)
// Every strategy ends at the clamp of every element before giving up (the clamp is PSD). The
// predicted decrease is the model actually solved: −(gᵀs + ½sᵀKs) for the step s taken, K the
// projected Hessian of the solve (newton_loop.cpp), exact or not.
#pragma once

#include "../stepper_settings.hpp"
#include "../../problems/element_hessians.hpp"
#include "../../problems/problem.hpp"

#include <string>

namespace xb {

// The values of xpbd.hessian_projection, parsed once (parse_projection_strategy).
enum class ProjectionStrategyKind { clamp, abs, adaptive, on_demand, progressive, rho_switch };
// Throws xb::Error for an unknown name (the valid ones: hessian_projection_choices()).
ProjectionStrategyKind parse_projection_strategy(const std::string& name);

class ProjectionStrategy {
 public:
  ProjectionStrategy(const Problem& prob, ProjectionStrategyKind kind, double exact_below);
  ProjectionStrategyKind kind() const { return kind_; }
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
  ProjectionStrategyKind kind_;
  double exact_below_;
  bool model_held_ = true;          // rho_switch
  static constexpr double max_tau = 1e3;  // progressive: τ at which every element is exact
  double tau_ = 1;                  // progressive: the tolerated negative curvature
};

}  // namespace xb
