// The stepper's settings (Algorithm 4 around the methods): the outer loop's iterations, stop test
// and global step, the form of the linear step, and the OpenMP threads of a run.
#pragma once

#include "../core/settings.hpp"

#include <string>

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
  // dual residual, harness/sim/line_search.hpp; ω unused).
  std::string step = "fixed";
  int threads = 0;  // OpenMP threads, 0 = OpenMP's default
  // The form of every global method's linear step: dual (A Δλ = b) | primal (K Δx = Jᵀα̃⁻¹b,
  // then Δλ = α̃⁻¹(b − JΔx); needs every α̃ > 0) | auto (primal when every α̃ > 0, else dual).
  std::string form = "auto";
};

const SettingTable<StepperSettings>& stepper_settings();

}  // namespace xb
