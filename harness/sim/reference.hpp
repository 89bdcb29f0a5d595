// The reference solution of one substep, for error-against-run-time plots (reference.method):
//  - newton (the default where every α̃ > 0): the solution of the time step itself, the minimiser of
//    the incremental potential E (harness/sim/newton.hpp) over the ground planes' bounds — the
//    stepper's own Newton loop (harness/sim/newton_loop.hpp) with CHOLMOD on the primal form
//    (projection `projection` below; reference.linear = mgpbd | jacobi-pcg: that method, to a
//    tolerance Eisenstat–Walker tightens down to 1e-12), from x̃, until ‖∇E‖ (the free gradient)
//    ≤ 1e-10 of its value at x̃ or at its rounding floor, at most 100 iterations
//    (ReferenceSettings); the iterate with the smallest ‖∇E‖ is the reference.
//  - xpbd (the default where some constraint is rigid, α̃ = 0): XPBD's own fixed point — CHOLMOD on
//    A Δλ = −(C + α̃λ), full step ω = 1, from x̃ with λ = 0, until the dual residual falls to 1e-10 of
//    its first value or stops improving (no 1% gain over 5 iterations), at most 100 iterations;
//    the iterate with the smallest dual residual is the reference.
// xpbd applies the stepper's colliders after each step; newton has them as bounds of the minimisation.
// Every newton reference carries its certificate (harness/sim/certificate.hpp): the proof that it
// is a minimiser and a bound on its own position error, in the units of position_error. A
// reference is trusted for a position-error threshold e only where it is certified and that bound
// is at most e/trust_margin (ReferenceSolution::trusted); xpbd references are never certified.
#pragma once

#include "certificate.hpp"
#include "forcing.hpp"
#include "global_step.hpp"
#include "newton_loop.hpp"

#include "../../problems/dual_system.hpp"
#include "../params.hpp"
#include "../../problems/problem.hpp"
#include "../../solvers/linear_solver.hpp"

#include <memory>
#include <optional>
#include <string>
#include <variant>

namespace xb {

// One substep's reference and everything recorded of it (the records' reference/ group,
// results/README.md): the one carrier of its certificate, which a cache of references stores whole.
struct ReferenceSolution {
  Eigen::Matrix3Xd x;                  // reference positions
  double dual_residual = 0;            // ‖C + α̃λ‖₂ of the reference (0 for newton: λ = −α̃⁻¹C)
  double relative_dual_residual = 0;   // over its value at x̃
  double relative_energy_gradient = -1;  // ‖∇E‖ over its value at x̃ (−1 where some α̃ = 0)
  int iterations = 0;                  // direct solves done
  // newton: the loop's stop reason; xpbd: converged | stagnated | max_iterations | solver_failed |
  // not_finite. stop_reason_success(status) says whether it is a solution.
  StopReason status = StopReason::running;
  // position_error's denominator: max(‖x_ref − x̃‖_M, √ε·L·‖1‖_M), L the diagonal of the free
  // particles' bounding box at x̃ and ‖1‖_M² their mass: the correction's size, or where the
  // substep barely corrects x̃ (free fall) √ε of the body's, so that the error does not blow up.
  double error_scale = 0;
  // The certificate (newton; certificate.hpp): ‖∇E‖ (free) and its rounding floor, N; the error
  // bound over error_scale (∞: none); certified: K positive definite on the free set and a bound.
  double energy_gradient = 0, gradient_floor = 0;
  double error_estimate = INFINITY;
  double contraction = NAN;  // q of the bound (the chord step's contraction)
  bool certified = false;
  std::string certificate_note;  // why it is not certified

  static constexpr double trust_margin = 100;
  // The finest position-error threshold the reference supports: trust_margin × error_estimate
  // where certified, ∞ otherwise.
  double certified_threshold() const { return certified ? trust_margin * error_estimate : INFINITY; }
  bool trusted(double threshold) const { return certified_threshold() <= threshold; }
};

// How far a newton reference goes (defaults: the ReferenceSolver constants).
struct ReferenceSettings {
  double target_relative = 1e-10;
  int max_iterations = 100;
};

// Every field of ReferenceSolution but x, by name: what a stored reference carries
// (harness/sim/reference_store.hpp; `run --reference-file`). A new field is one line here.
using ReferenceMember = std::variant<double ReferenceSolution::*, int ReferenceSolution::*, bool ReferenceSolution::*,
                                     std::string ReferenceSolution::*, StopReason ReferenceSolution::*>;
struct ReferenceField {
  const char* name;
  ReferenceMember member;
};
inline const ReferenceField reference_fields[] = {
    {"dual_residual", &ReferenceSolution::dual_residual},
    {"relative_dual_residual", &ReferenceSolution::relative_dual_residual},
    {"relative_energy_gradient", &ReferenceSolution::relative_energy_gradient},
    {"iterations", &ReferenceSolution::iterations},
    {"status", &ReferenceSolution::status},
    {"error_scale", &ReferenceSolution::error_scale},
    {"energy_gradient", &ReferenceSolution::energy_gradient},
    {"gradient_floor", &ReferenceSolution::gradient_floor},
    {"error_estimate", &ReferenceSolution::error_estimate},
    {"contraction", &ReferenceSolution::contraction},
    {"certified", &ReferenceSolution::certified},
    {"certificate_note", &ReferenceSolution::certificate_note},
};

// reference.method as run: auto resolved (newton where every α̃ > 0, else xpbd); throws xb::Error
// for newton with a rigid constraint.
std::string resolve_reference_method(const std::string& requested, const Eigen::VectorXd& alpha_tilde);
// What the recorder writes as reference_method, for these parameters.
std::string reference_description(const Params& p, const Eigen::VectorXd& alpha_tilde);

class ReferenceSolver {
 public:
  static constexpr double target_relative = 1e-10;
  static constexpr int max_iterations = 100;
  static constexpr int stagnation_window = 5;
  // newton: the projection strategy of its loop (harness/sim/hessian_projection.hpp).
  static constexpr const char* projection = "progressive";

  // `prob` and `alpha_tilde` must outlive the solver; only the problem's topology, masses and
  // colliders are used. Throws xb::Error for reference.method = newton with a rigid constraint.
  ReferenceSolver(const Problem& prob, const Params& p, const Eigen::VectorXd& alpha_tilde,
                  const ReferenceSettings& settings = {});
  ReferenceSolution solve(const Eigen::Matrix3Xd& x_pred);
  // newton: the certificate of any x for the substep predicted at x_pred. Throws xb::Error for an
  // xpbd reference.
  Certificate certify(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);
  // What the recorder writes as reference_method.
  std::string description() const { return description_; }
  const std::string& method() const { return method_; }

 private:
  ReferenceSolution solve_xpbd(const Eigen::Matrix3Xd& x_pred);
  ReferenceSolution solve_newton(const Eigen::Matrix3Xd& x_pred);

  const Problem& prob_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  std::string method_, description_;
  DualSystem ds_;
  std::unique_ptr<LinearSolver> direct_;  // xpbd
  Params newton_params_;
  std::optional<GlobalStep> newton_;      // newton
  std::optional<NewtonLoop> loop_;        // newton: the stepper's Newton loop on newton_
  std::optional<MinimiserCertificate> certificate_;  // newton
  std::optional<ForcingRule> forcing_;    // newton with an iterative reference.linear
  bool first_setup_ = true;
};

// ‖a − b‖_M = sqrt(Σ_p m_p |a_p − b_p|²) over free particles (m_p = 1/w_p; pins carry no mass).
double mass_norm_distance(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b);
// ReferenceSolution::error_scale for a reference x_ref of the substep predicted at x_pred.
double position_error_scale(const Problem& prob, const Eigen::Matrix3Xd& x_ref, const Eigen::Matrix3Xd& x_pred);

}  // namespace xb
