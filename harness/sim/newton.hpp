// Newton's method on the incremental potential of one substep (§1.5 of the supplemental, Eq. 14–15):
//   E(x) = ‖x − x̃‖²_M/(2h²) + ½ C(x)ᵀα⁻¹C(x),   h²∇E = M(x − x̃) + ∇Cᵀα̃⁻¹C,
//   h²∇²E = M + ∇Cᵀα̃⁻¹∇C + Σ_j (C_j/α̃_j) ∇²C_j.
// With the multipliers eliminated, λ = −α̃⁻¹C(x) (so h = C + α̃λ = 0), the primal residual of Eq. 4,
// g = M(x − x̃) − ∇Cᵀλ, is h²∇E, and the primal form of the KKT step with the geometric stiffness
// M − Σλ_j∇²C_j and g kept, K Δx = Jᵀα̃⁻¹b − g with b = −h = 0, is the Newton step h²∇²E Δx = −h²∇E:
// `step = newton` is Newton on E, projected where the element Hessians are (docs/newton.md).
// Here: g and the Newton residual every method logs, the elimination, ‖∇E‖ and its rounding floor.
// The loop itself: newton_loop.hpp.
#pragma once

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <Eigen/Dense>

namespace xb {

// Newton evaluates the constraints without tet ARAP's gradient cut at rest (problems/constraints.hpp):
// C∇C, the gradient of ½C², is smooth there.
constexpr double newton_rest_epsilon = 0;

// g = M(x − x̃) − ∇Cᵀλ per particle, zero columns at pins.
void primal_residual_vector(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& lambda,
                            Eigen::Matrix3Xd& g);

// λ = −α̃⁻¹C (every α̃ > 0): the multipliers of x, with which g = h²∇E.
void eliminate_multipliers(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, Eigen::VectorXd& lambda);

// A bound on the rounding error of the computed h²∇E = M(x − x̃) + Jᵀα̃⁻¹C at x, in the units of
// ‖g‖: C_j is computed from coordinates of size X_j (the largest |x| of its particles), so it
// carries an error of about ε·X_j·‖∇C_j‖, which α̃_j⁻¹∇C_j carries into the gradient; with the
// inertia's ε·m_p|x_p|, per particle ε(m_p|x_p| + Σ_j |∇_pC_j|·X_j‖∇C_j‖/α̃_j), and its 2-norm over
// the free particles. Below it ‖∇E‖ is noise: the stop reason rounding_floor (stop_reason.hpp).
double gradient_rounding_floor(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                               const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde);
// One sample of that rounding as it arises, per particle (0 at pins): each C_j off by ±ε·X_j‖∇C_j‖
// carried by α̃_j⁻¹∇C_j, each inertia term by ±ε·m_p|x_p|, the signs fixed by a hash of the index
// (the same sample every call). Its Newton step is the step that g's rounding makes
// (harness/sim/certificate.hpp); the floor's absolute values would lose the directions.
void gradient_rounding_sample(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                              const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, Eigen::Matrix3Xd& n);

// The rounding of the computed E at x (harness/sim/residual_energy.hpp), by the floor's model: each
// term's error from its inputs' rounding — the inertia's m_p|x_p − x̃_p|·ε(|x_p| + |x̃_p|)/h², each
// constraint's |C_j|·ε·X_j‖∇C_j‖/α_j — summed as independent errors (their 2-norm), plus ε·E for
// the products and the sum. A change of E below it is noise (the line search's trapezoid test).
double energy_rounding(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& x_pred, double h, double energy);

// ‖∇E(x)‖ from the constraint state at x: ‖M(x − x̃) + ∇Cᵀα̃⁻¹C‖/h² over free particles.
double energy_gradient_norm(const Problem& prob, const DualSystem& ds, const ConstraintState& s,
                            const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                            const Eigen::VectorXd& alpha_tilde, double h);

// Σ over free particles of a_p·b_p (the directional derivative g·Δx).
double particle_dot(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b);

}  // namespace xb
