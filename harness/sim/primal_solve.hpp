// A linear solver run on the primal form of a dual system (problems/primal_system.hpp): K is
// filled and handed to the solver with block size 3 and the rigid-body modes; the solve is judged
// by the dual residual it implies (linear.stop_norm = dual; primal and energy leave the solver its
// own norm on K), and Δλ is recovered. Everything — assembly of K, setup, solve,
// recovery — is inside the reported setup_time + solve_time, so both forms are timed alike.
#pragma once

#include "../../problems/primal_system.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/solver_settings.hpp"

#include <functional>
#include <memory>

namespace xb {

// The top-left block M̃ of the step when it is not M (xpbd.geometric_stiffness, docs/newton.md):
// `fill` fills K in place of K = M + Jᵀα̃⁻¹J (the same pattern); a diagonal M̃ gives its inverse per
// free DOF (3 per free particle), so that the dual residual stays −J M̃⁻¹ r_K; a full M̃ has no
// cheap inverse and no dual system: the solve is judged by K's own relative residual ‖r_K‖/‖f‖,
// which for Newton on E is the inexact-Newton test ‖∇²E Δx + ∇E‖ ≤ η‖∇E‖.
struct TopLeftBlock {
  std::function<void(PrimalSystem&)> fill;  // empty: K = M + Jᵀα̃⁻¹J
  const Vector* inv_mass = nullptr;         // diagonal M̃: its inverse per free DOF; null with fill: full
  bool full() const { return fill && !inv_mass; }
};

class PrimalSolve {
 public:
  // linear: the tolerance (until set_tolerance) and the stop norm.
  PrimalSolve(std::unique_ptr<LinearSolver> solver, ConstraintGraph graph, const LinearSettings& linear);

  // Fills K from the gradients (kept by reference until the next setup) and sets the solver up
  // with the rigid modes at positions x. Throws xb::Error if some α̃ ≤ 0.
  // `top`: M̃ in K's top-left block (copied; its inv_mass must outlive the solves).
  void setup(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& x, SetupKind kind,
             SetupContext ctx, const TopLeftBlock& top = {});
  // setup()'s fill of K alone (the solver is not set up; a solve() after it needs a setup()).
  void fill(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const TopLeftBlock& top = {});
  // Δλ for A Δλ = b. Statistics in dual terms: iterations summed over refinement rounds,
  // final_relative_residual = ‖b − AΔλ‖₂/‖b‖₂ (through −J M⁻¹ r_K), setup_time that of setup().
  // With g (the primal residual, one 3-block per free particle: xpbd.primal_residual = keep) the
  // step is K Δx = Jᵀα̃⁻¹b − g, the dual system's right-hand side b + J M̃⁻¹g; dx, if given, gets Δx.
  LinearStats solve(const Vector& b, Vector& dlambda, const Vector* g = nullptr, Vector* dx = nullptr);
  // The tolerance of the following solves (the solver's and the refinement's).
  void set_tolerance(double tol);

  LinearSolver& solver() { return *solver_; }
  // Seconds the last setup() spent filling K (part of its setup_time).
  double fill_time() const { return fill_time_; }
  const PrimalSystem& system() const { return sys_; }

 private:
  double dual_relative(const Vector& r_K);
  const Vector& inverse_mass();  // M̃⁻¹ per free DOF (M⁻¹ unless the top-left block gives its own)

  std::unique_ptr<LinearSolver> solver_;
  PrimalSystem sys_;
  double tol_;
  bool stop_on_dual_;                // linear.stop_norm = dual
  bool solver_judges_dual_ = false;  // its Krylov loop stops on the dual residual itself
  const Gradients* grad_ = nullptr;
  const Eigen::VectorXd* alpha_tilde_ = nullptr;
  TopLeftBlock top_;  // of the last setup
  double bnorm_ = 0, setup_time_ = 0, fill_time_ = 0;
  Vector work_, scaled_, minv_;
};

}  // namespace xb
