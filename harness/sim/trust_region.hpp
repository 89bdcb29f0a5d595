// The trust-region globalisation of Newton on E (xpbd.globalization = trust_region, and
// reference.globalization; docs/newton.md): each iteration minimises the quadratic model of the
// exact Hessian, m(p) = h²∇Eᵀp + ½pᵀKp with K = h²∇²E unprojected (indefinite where elements
// are), inside a region ‖p‖ ≤ Δ, then judges the step by ρ = (E(x) − E(x + p))/(−m(p)/h²), the
// decrease the model actually solved predicted (Nocedal–Wright, Numerical Optimization, ch. 4):
//   ρ ≤ η (η = 0.01)   the step is rejected and Δ shrinks; the model is solved again
//   ρ < 1/4            Δ ← ¼·min(Δ, ‖p‖)
//   ρ > 3/4 on ‖p‖ = Δ Δ ← 2Δ
// The subproblem (xpbd.trust_region_subproblem):
//   steihaug        Steihaug–Toint CG on K (solvers/krylov/steihaug.hpp), preconditioned by the
//                   run's linear method set up on the clamped K (mgpbd's V-cycle, Jacobi, CHOLMOD's
//                   factor); the region in that preconditioner's norm (K_c's with CHOLMOD); the step
//                   against the elements' negative-curvature modes, alone or from an interior step to
//                   the boundary, whichever lowers the model most (harness/sim/negative_curvature.hpp)
//   more_sorensen   K + σK_c factorised by CHOLMOD, σ by the secular equation
//                   (solvers/direct/more_sorensen.hpp); the region in the clamped K's norm ‖p‖_{K_c},
//                   so that its path runs from the clamped Newton step (σ → ∞) to the exact one (σ = 0)
// Where E's computed change is within its rounding, the decrease is measured by the trapezoid rule on
// the gradients, as the robust line search does (energy_line_search.hpp).
#pragma once

#include <string>

namespace xb {

enum class Globalization { line_search, trust_region };
enum class TrustRegionSubproblem { steihaug, more_sorensen };
// Throw xb::Error naming the key for an unknown value.
Globalization parse_globalization(const std::string& name, const std::string& key);
TrustRegionSubproblem parse_trust_region_subproblem(const std::string& name, const std::string& key);

// The radius rule and the acceptance test (the constants above).
struct RadiusRule {
  static constexpr double accept = 0.01, shrink_below = 0.25, grow_above = 0.75;
  static constexpr double shrink = 0.25, grow = 2;
  static bool accepted(double rho) { return rho > accept; }  // NaN: rejected
  // Δ for the next try or iteration after a step of norm `step` (on the boundary or not) with ratio ρ.
  static double next(double radius, double rho, double step, bool boundary);
};

// Giving up: every step rejected until Δ fell below this fraction of the substep's first radius.
constexpr double trust_region_min_radius = 1e-12;

}  // namespace xb
