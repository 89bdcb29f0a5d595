// A linear solver run on the primal form of a dual system (problems/primal_system.hpp): K is
// filled and handed to the solver with block size 3 and the rigid-body modes; the solve is judged
// by the dual residual it implies (linear.stop_norm = dual; primal and energy leave the solver its
// own norm on K), and Δλ is recovered. Everything — assembly of K, setup, solve,
// recovery — is inside the reported setup_time + solve_time, so both forms are timed alike.
#pragma once

#include "../../problems/primal_system.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/solver_settings.hpp"

#include <memory>

namespace xb {

class PrimalSolve {
 public:
  // linear: the tolerance (until set_tolerance) and the stop norm.
  PrimalSolve(std::unique_ptr<LinearSolver> solver, ConstraintGraph graph, const LinearSettings& linear);

  // Fills K from the gradients (kept by reference until the next setup) and sets the solver up
  // with the rigid modes at positions x. Throws xb::Error if some α̃ ≤ 0.
  void setup(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& x, SetupKind kind,
             SetupContext ctx);
  // Δλ for A Δλ = b. Statistics in dual terms: iterations summed over refinement rounds,
  // final_relative_residual = ‖b − AΔλ‖₂/‖b‖₂ (through −J M⁻¹ r_K), setup_time that of setup().
  LinearStats solve(const Vector& b, Vector& dlambda);
  // The tolerance of the following solves (the solver's and the refinement's).
  void set_tolerance(double tol);

  LinearSolver& solver() { return *solver_; }
  // Seconds the last setup() spent filling K (part of its setup_time).
  double fill_time() const { return fill_time_; }
  const PrimalSystem& system() const { return sys_; }

 private:
  double dual_relative(const Vector& r_K);

  std::unique_ptr<LinearSolver> solver_;
  PrimalSystem sys_;
  double tol_;
  bool stop_on_dual_;                // linear.stop_norm = dual
  bool solver_judges_dual_ = false;  // its Krylov loop stops on the dual residual itself
  const Gradients* grad_ = nullptr;
  const Eigen::VectorXd* alpha_tilde_ = nullptr;
  double bnorm_ = 0, setup_time_ = 0, fill_time_ = 0;
  Vector work_;
};

}  // namespace xb
