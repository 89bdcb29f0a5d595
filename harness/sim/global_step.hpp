// The linear step of the global methods with XPBD's two simplifications as switches (Eq. 5–9 of
// the supplemental, docs/newton.md). The KKT step at (x, λ), g = M(x − x̃) − ∇Cᵀλ, h = C + α̃λ:
//   [ M̃  −Jᵀ ] [Δx]     [g]
//   [ J    α̃ ] [Δλ] = − [h],   M̃ = ∂g/∂x = M − Σ_j λ_j ∇²C_j   (J = ∇C)
// xpbd.geometric_stiffness: M̃ = M (none, XPBD's), M + K̃_d (diagonal), the whole, each part
// PSD-projected (full); xpbd.primal_residual: g = 0 on the right (zero, XPBD's) or kept (keep).
//   dual:   (J M̃⁻¹Jᵀ + α̃)Δλ = −h + J M̃⁻¹g,   Δx = M̃⁻¹(JᵀΔλ − g)      (M̃ diagonal)
//   primal: (M̃ + Jᵀα̃⁻¹J)Δx = Jᵀα̃⁻¹(−h) − g,   Δλ = α̃⁻¹(−h − JΔx)    (every α̃ > 0)
// With none and zero this is today's step, computed the same way (Δx = M⁻¹JᵀΔλ in both forms).
// Under step = newton (λ = −α̃⁻¹C, harness/sim/newton.hpp) `full` assembles M + Σ_j π(H_j), each
// element's whole energy Hessian H_j = (∇C_j∇C_jᵀ + C_j∇²C_j)/α̃_j projected (less than projecting
// its geometric part alone, and equal to it unprojected); otherwise M + Σ_j π(−λ_j∇²C_j) + Jᵀα̃⁻¹J.
#pragma once

#include "primal_solve.hpp"

#include "../params.hpp"
#include "../../problems/dual_system.hpp"
#include "../../problems/element_hessians.hpp"
#include "../../problems/problem.hpp"
#include "../../solvers/linear_solver.hpp"

#include <memory>
#include <optional>
#include <string>

namespace xb {

struct GlobalStepInput {
  const ConstraintState& state;  // C, ∇C at x
  const Eigen::VectorXd& lambda;
  const Eigen::Matrix3Xd& x;
  const Eigen::Matrix3Xd& g;     // the primal residual per particle (read with primal_residual = keep)
  const Vector& b;               // −h = −(C + α̃λ)
  Projection projection;         // of the element matrices (full): clamp | abs | none (exact)
  // step = newton only: the per-element choice (overrides `projection`; harness/sim/hessian_projection.hpp),
  // and the particles whose y the step holds (contact's active bounds, harness/sim/plane_bounds.hpp).
  const ElementProjection* elements = nullptr;
  const std::vector<int>* held = nullptr;
  // step = newton: `state` came from elements()->evaluate(x): its tet SVDs are reused in the fill.
  bool evaluated = false;
};

class GlobalStep {
 public:
  // Throws xb::Error for a combination that does not exist (full in the dual form).
  GlobalStep(const Problem& prob, DualSystem& ds, const std::string& method, const Params& p,
             const Eigen::VectorXd& alpha_tilde);

  const std::string& form() const { return form_; }
  LinearSolver& solver() { return primal_ ? primal_->solver() : *solver_; }
  const PrimalSolve* primal() const { return primal_ ? &*primal_ : nullptr; }
  void set_tolerance(double tol);
  // Fills the top-left block at (x, λ) and the dual form's A; returns the seconds spent. The
  // primal form fills K inside solve()'s setup (timed there, as the solvers' setup_time).
  double prepare(const GlobalStepInput& in);
  // Sets the solver up on the prepared system and solves; Δλ and Δx (per particle, 0 at pins).
  LinearStats solve(const GlobalStepInput& in, SetupKind kind, SetupContext ctx, Vector& dlambda,
                    Eigen::Matrix3Xd& dx);
  // step = newton: fills K from the prepared element blocks (holding in.held's y) and sets the
  // solver up on it, without a solve (the trust region's preconditioner). Throws xb::Error otherwise.
  void setup(const GlobalStepInput& in, SetupKind kind, SetupContext ctx);
  // K's rows the last step = newton setup held (contact's active bounds).
  const std::vector<int>& held_dofs() const { return held_dofs_; }
  // Seconds filling K in the last primal setup.
  double primal_fill_time() const { return primal_ ? primal_->fill_time() : 0; }
  // step = newton: sᵀKs for a step s per particle, K the last one filled (held dofs' s ignored):
  // the curvature term of the quadratic model the step solved.
  double curvature(const Eigen::Matrix3Xd& s);
  // step = newton: K = M + Σπ(H_j) at in.x with in's projection and held bounds, filled without a
  // solver setup, and g on its free dofs (the held ones 0): the certificate's system
  // (harness/sim/certificate.hpp). K's rows: 3 per particle of primal()->system().free_particles().
  const SparseMatrix& fill_newton_system(const GlobalStepInput& in, Vector& g_dof);
  // The element matrices of the last prepare() (geometric_stiffness = diagonal | full), or null.
  const ElementHessians* elements() const { return elements_ ? &*elements_ : nullptr; }
  ElementHessians* elements() { return elements_ ? &*elements_ : nullptr; }

 private:
  void dual_step(const GlobalStepInput& in, const Vector& dlambda, Eigen::Matrix3Xd& dx);
  void setup_primal(const GlobalStepInput& in, SetupKind kind, SetupContext ctx);
  // step = newton: held_dofs_ from in.held and top_ filling M + Σπ(H_j) with them held.
  void newton_top(const GlobalStepInput& in);
  // The free dofs' values of per-particle v (held dofs 0).
  void to_dofs(const Eigen::Matrix3Xd& v, Vector& out) const;

  const Problem& prob_;
  DualSystem& ds_;
  const Eigen::VectorXd& alpha_tilde_;
  std::string form_, stiffness_;
  bool keep_, newton_;
  std::unique_ptr<LinearSolver> solver_;  // the dual form's
  std::optional<PrimalSolve> primal_;     // or the primal form's
  Eigen::Matrix3Xd minv_;                 // M̃⁻¹ per particle and axis (diagonal; 0 at pins)
  Eigen::Matrix3Xd kd_;                   // K̃_d per particle and axis (diagonal)
  std::optional<ElementHessians> elements_;  // diagonal, full
  Vector minv_dof_, g_dof_, dx_dof_, rhs_, work_dofs_;  // the primal form's per free DOF
  std::vector<int> held_dofs_;              // K's rows of the held y coordinates
  TopLeftBlock top_;
  Eigen::Matrix3Xd work_;
};

}  // namespace xb
