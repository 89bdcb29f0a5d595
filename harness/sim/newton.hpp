// Newton's method on the incremental potential of one substep (§1.5 of the supplemental, Eq. 14–15):
//   E(x) = ‖x − x̃‖²_M/(2h²) + ½ C(x)ᵀα⁻¹C(x),   h²∇E = M(x − x̃) + ∇Cᵀα̃⁻¹C,
//   h²∇²E = M + ∇Cᵀα̃⁻¹∇C + Σ_j (C_j/α̃_j) ∇²C_j.
// With the multipliers eliminated, λ = −α̃⁻¹C(x) (so h = C + α̃λ = 0), the primal residual of Eq. 4,
// g = M(x − x̃) − ∇Cᵀλ, is h²∇E, and the primal form of the KKT step with the geometric stiffness
// M − Σλ_j∇²C_j and g kept, K Δx = Jᵀα̃⁻¹b − g with b = −h = 0, is the Newton step h²∇²E Δx = −h²∇E:
// `step = newton` is Newton on E, projected where the element Hessians are (docs/newton.md).
// Here: g and the Newton residual every method logs, the elimination, and the line search on E.
#pragma once

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <Eigen/Dense>

namespace xb {

// g = M(x − x̃) − ∇Cᵀλ per particle, zero columns at pins.
void primal_residual_vector(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& lambda,
                            Eigen::Matrix3Xd& g);

// λ = −α̃⁻¹C (every α̃ > 0): the multipliers of x, with which g = h²∇E.
void eliminate_multipliers(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, Eigen::VectorXd& lambda);

constexpr double armijo_c = 1e-4;             // sufficient decrease: E(x + tΔx) ≤ E(x) + c t ∇E·Δx
constexpr double energy_search_min_step = 1e-9;  // below it the search has failed (30 halvings)
// When the predicted decrease |t ∇E·Δx| is below this multiple of the rounding of E, E cannot tell
// the trial from x: the test is then on the gradient, ‖∇E(x + tΔx)‖ ≤ (1 − c t)‖∇E(x)‖, with E not
// above E(x) by more than that rounding.
constexpr double energy_rounding_factor = 1e3;

struct EnergySearch {
  double t = 0;          // the step taken (0: failed, x stays)
  int trials = 0;        // energy (and gradient) evaluations spent
  bool accepted = false;
  bool on_gradient = false;  // the last test was the gradient's (rounding regime)
  double energy = 0;     // E at x + tΔx (or at x if failed)
};

// Backtracking on E along dx from x (t = 1, 1/2, …): slope = ∇E(x)·dx must be < 0 (else it fails
// at once, no trial); `energy` = E(x), `grad_norm` = ‖∇E(x)‖. Does not change x. Trials are not
// projected onto colliders (the stepper does that after the step, as for the other steps).
EnergySearch armijo_on_energy(const Problem& prob, const DualSystem& ds, const Eigen::Matrix3Xd& x,
                              const Eigen::Matrix3Xd& dx, const Eigen::Matrix3Xd& x_pred,
                              const Eigen::VectorXd& alpha_tilde, double h, double energy, double slope,
                              double grad_norm, ConstraintState& scratch, Eigen::Matrix3Xd& x_trial);

// ‖∇E(x)‖ from the constraint state at x: ‖M(x − x̃) + ∇Cᵀα̃⁻¹C‖/h² over free particles.
double energy_gradient_norm(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                            const Eigen::VectorXd& alpha_tilde, double h);

// Σ over free particles of a_p·b_p (the directional derivative g·Δx).
double particle_dot(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b);

}  // namespace xb
