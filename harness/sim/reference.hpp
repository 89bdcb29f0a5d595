// The reference solution of one substep, for error-against-run-time plots: the substep solved
// by the global direct method (Goldenthal's fast projection: CHOLMOD on A Δλ = −(C + α̃λ), full
// step ω = 1, the same formulation and colliders as the stepper), started from the substep's
// predicted state x̃ with λ = 0, iterated until the dual residual falls to 1e-10 of its first
// value or stops improving (no 1% gain over 5 iterations), at most 100 outer iterations.
// The best iterate (smallest dual residual) is the reference.
#pragma once

#include "../../problems/dual_system.hpp"
#include "../params.hpp"
#include "../../problems/problem.hpp"
#include "../../solvers/linear_solver.hpp"

#include <memory>
#include <string>

namespace xb {

struct ReferenceSolution {
  Eigen::Matrix3Xd x;                  // reference positions
  double dual_residual = 0;            // ‖C + α̃λ‖₂ of the reference
  double relative_dual_residual = 0;   // over its value at x̃
  int iterations = 0;                  // direct solves done
  std::string status;                  // converged | stagnated | max_iterations | failed
};

// What the recorder writes as reference_method.
std::string reference_method_description();

class ReferenceSolver {
 public:
  static constexpr double target_relative = 1e-10;
  static constexpr int max_iterations = 100;
  static constexpr int stagnation_window = 5;

  // `prob` must outlive the solver; only its topology, masses and colliders are used.
  ReferenceSolver(const Problem& prob, const Params& p);
  ReferenceSolution solve(const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& alpha_tilde);

 private:
  const Problem& prob_;
  DualSystem ds_;
  std::unique_ptr<LinearSolver> direct_;
  bool first_setup_ = true;
};

// ‖a − b‖_M = sqrt(Σ_p m_p |a_p − b_p|²) over free particles (m_p = 1/w_p; pins carry no mass).
double mass_norm_distance(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b);

}  // namespace xb
