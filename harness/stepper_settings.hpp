// The stepper's settings (Algorithm 4 around the methods): the outer loop's iterations, stop test
// and global step, the form of the linear step, and the OpenMP threads of a run.
#pragma once

#include "../core/settings.hpp"

#include <string>
#include <vector>

namespace xb {

struct StepperSettings {
  int max_iterations = 100;  // outer iterations per substep
  double rtol = 1e-6;        // stop when ‖C+α̃λ‖ ≤ rtol·(its value at iteration 0)
  double atol = 1e-12;       // or when ‖C+α̃λ‖ ≤ atol
  double omega = 1.0;        // global step x += ω M⁻¹∇CᵀΔλ (paper's code: 0.1 soft, 0.25 cloth)
  // Which dual residual the stop test (rtol/atol) reads: true ‖C(x_k) + α̃λ_k‖ | authors (the
  // quantity the authors' code logs, harness/io/run_result.hpp: IterationLog::authors_dual_residual).
  std::string residual_metric = "true";
  // Global step: fixed (x += ω M⁻¹∇CᵀΔλ, λ += Δλ) | line_search (the authors' backtracking on the
  // dual residual, harness/sim/line_search.hpp; ω unused) | newton (Newton's method on the incremental
  // potential E(x), harness/sim/newton.hpp: λ = −C(x)/α̃ at every iterate, an Armijo backtracking
  // line search on E, and rtol/atol read ‖∇E‖ instead of the dual residual; needs every α̃ > 0 and
  // primal_residual = keep).
  std::string step = "fixed";
  int threads = 0;  // OpenMP threads, 0 = OpenMP's default
  // The form of every global method's linear step: dual (A Δλ = b) | primal (K Δx = Jᵀα̃⁻¹b,
  // then Δλ = α̃⁻¹(b − JΔx); needs every α̃ > 0) | auto (primal when every α̃ > 0, else dual).
  std::string form = "auto";
  // XPBD's two simplifications of the Newton step on the KKT system (Eq. 6 of the supplemental), as
  // switches (docs/newton.md). geometric_stiffness: the top-left block M̃ = M − Σ λ_j ∇²C_j is M (none,
  // XPBD's), M + K̃_d (diagonal: per particle the non-negative diagonal of that sum) or the whole
  // sum, each constraint's part made positive semi-definite (full; primal form only).
  std::string geometric_stiffness = "none";
  // primal_residual: g = M(x − x̃) − ∇Cᵀλ left out of the step's right-hand side (zero, XPBD's) or
  // kept (keep): dual (∇C M̃⁻¹∇Cᵀ + α̃)Δλ = −h + ∇C M̃⁻¹g, Δx = M̃⁻¹(∇CᵀΔλ − g); primal K Δx = Jᵀα̃⁻¹b − g.
  std::string primal_residual = "zero";
  // How each element's part of the geometric stiffness is made PSD (full): clamp (negative
  // eigenvalues to 0) | abs (to their absolute value) | adaptive (step = newton: clamp until ‖∇E‖ falls
  // below exact_hessian_below of its first value, then the exact Hessian while it gives a descent
  // direction, clamp again for a step where it does not).
  // on_demand, progressive and rho_switch are strategies of step = newton (harness/sim/hessian_projection.hpp).
  std::string hessian_projection = "clamp";
  double exact_hessian_below = 1e-2;
  // step = newton's line search on E (harness/sim/energy_line_search.hpp): robust_armijo | armijo.
  std::string line_search = "robust_armijo";
  // step = newton's globalisation (harness/sim/trust_region.hpp): line_search (the projection
  // strategy's step, then xpbd.line_search) | trust_region (the exact Hessian's model in a region,
  // its subproblem solved by trust_region_subproblem: steihaug | more_sorensen).
  std::string globalization = "line_search";
  std::string trust_region_subproblem = "steihaug";
  // The reference solution of --reference (harness/sim/reference.hpp): newton (Newton on E, the
  // backward-Euler solution; every α̃ > 0) | xpbd (XPBD's fixed point by CHOLMOD) | auto (newton
  // where every α̃ > 0, else xpbd).
  std::string reference_method = "auto";
  // The linear method of the newton reference's solves: cholmod (exact) | mgpbd | jacobi-pcg
  // (iterative, to a tolerance that Eisenstat–Walker tightens to 1e-12: for sizes whose factor does
  // not fit the machine). The reference's stop test on ‖∇E‖ is the same.
  std::string reference_linear = "cholmod";
  // The newton reference's globalisation and, with trust_region, its subproblem solver (steihaug
  // preconditioned by reference.linear on the clamped K, or more_sorensen by CHOLMOD).
  std::string reference_globalization = "line_search";
  std::string reference_trust_region_subproblem = "steihaug";
};

const SettingTable<StepperSettings>& stepper_settings();
// The values of xpbd.hessian_projection (harness/sim/hessian_projection.hpp).
const std::vector<std::string>& hessian_projection_choices();

}  // namespace xb
