// Second derivatives of single constraints and their positive semi-definite projections: what
// XPBD's linear step drops (the geometric stiffness, MGPBD supplemental §1.4) and what Newton's
// method on the incremental potential needs (§1.5).
//
// Sign convention (as in harness/sim/simulation.cpp and problems/dual_system.hpp): the step
// solves (J M⁻¹ Jᵀ + α̃)Δλ = b with b = −(C + α̃λ) and Δx = M⁻¹ JᵀΔλ, so at convergence
// λ = −α̃⁻¹C (a stretched constraint, C > 0, has λ < 0). The KKT residual is
// g = M(x − x̃) − Jᵀλ, whose Jacobian (the top-left block of Eq. 6) is
//   ∂g/∂x = M − Σ_j λ_j ∇²C_j = M + Σ_j G_j,     G_j = −λ_j ∇²C_j  (the geometric stiffness).
// With λ_j = −C_j/α̃_j, G_j = (C_j/α̃_j)∇²C_j and the whole Newton matrix is
//   M + Σ_j H_j,   H_j = (∇C_j∇C_jᵀ + C_j∇²C_j)/α̃_j = Δt²∇²(½C_j²/α_j),
// i.e. Δt²∇²E of E(x) = ‖x − x̃‖²_M/(2Δt²) + Σ ½C²/α (Eq. 14), whose gradient Δt²∇E is g at
// λ = −α̃⁻¹C. XPBD keeps M + Jᵀα̃⁻¹J (the Gauss–Newton part of Σ H_j), i.e. drops Σ G_j.
// Every matrix below is symmetric and in its constraint's gradient order (distance: p, q;
// tet: x0..x3), 3 rows per particle. Checked against finite differences of the gradients in
// tests/problems/test_constraint_hessian.cpp.
#pragma once

#include <Eigen/Dense>

#include <array>
#include <string>
#include <vector>

namespace xb {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;

// How an element matrix is made positive semi-definite, eigenvalue by eigenvalue:
// none (exact, unprojected), clamp (max(μ, 0)), abs (|μ|).
enum class Projection { none, clamp, abs };
const std::vector<std::string>& projection_choices();  // "none", "clamp", "abs"
// Throws xb::Error "WHERE: unknown projection 'NAME' (valid: none, clamp, abs)".
Projection parse_projection(const std::string& name, const std::string& where);
std::string projection_name(Projection p);
double project_eigenvalue(double mu, Projection p);

// The numeric projection of a symmetric matrix by a full eigendecomposition: the fallback where
// no closed form applies, and the tests' reference for the closed forms.
template <int N>
void project_symmetric(Eigen::Matrix<double, N, N>& A, Projection p) {
  if (p == Projection::none) return;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(A);
  Eigen::Matrix<double, N, 1> mu = es.eigenvalues();
  for (int i = 0; i < N; ++i) mu[i] = project_eigenvalue(mu[i], p);
  A = es.eigenvectors() * mu.asDiagonal() * es.eigenvectors().transpose();
}

// ---- Distance, C = |p − q| − l₀ (Eq. 13): ∇²C = [B −B; −B B], B = (I − nnᵀ)/l.
// At l = |p − q| = 0 the gradient is zero by convention (problems/constraints.hpp), and so is
// the Hessian (its 1/l has no limit): the constraint contributes nothing there.
Matrix6d distance_hessian(const Eigen::Vector3d& p, const Eigen::Vector3d& q);
// G = −λ∇²C: [B −B; −B B] with B = π(−λ/l)(I − nnᵀ) (eigenvalues 2(−λ/l) twice, else 0).
Matrix6d distance_geometric_stiffness(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double lambda, Projection proj);
// H = (∇C∇Cᵀ + C∇²C)/α̃: B = (nnᵀ + π(C/l)(I − nnᵀ))/α̃ (the stretch eigenvalue 2/α̃ is never
// negative; the transverse one 2C/(l α̃) is negative under compression). 0 at l = 0.
// C and ∇C (distance_constraint's) come out too where asked, and `smallest`: the smallest eigenvalue
// of the exact (unprojected) H in its own eigenbasis (negative: the element is indefinite).
// `tolerance` (≥ 0): proj applies only where the smallest eigenvalue is below −tolerance/α̃ (an
// element whose negative curvature is mild, relative to its own stiffness 1/α̃, stays exact).
Matrix6d distance_energy_hessian(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double rest, double alpha_tilde,
                                 Projection proj, double* C = nullptr, Eigen::Vector3d* grad_p = nullptr,
                                 Eigen::Vector3d* grad_q = nullptr, double* smallest = nullptr, double tolerance = 0);

// ---- Tet ARAP, C = ‖F − R‖_F (problems/constraints.hpp), Ψ = ½C² = ½‖F − R‖².
// With F = UΣVᵀ (rotation-variant: σ₁ ≥ σ₂ ≥ |σ₃|, so every σᵢ + σⱼ ≥ 0), ∇²_F Ψ has the
// closed-form eigensystem (Frobenius-orthonormal modes, vec column-major):
//   twist  U(eᵢeⱼᵀ − eⱼeᵢᵀ)Vᵀ/√2   ψ = 1 − 2/(σᵢ + σⱼ)   (the only ones that can be negative)
//   flip   U(eᵢeⱼᵀ + eⱼeᵢᵀ)Vᵀ/√2   ψ = 1
//   scale  U diag(s)Vᵀ, |s| = 1     ψ = 1
// ∇_F C = (F − R)/C = U diag(ĝ)Vᵀ, ĝ = (σ − 1)/C, lies in the scaling subspace, and
// ∇²_F C = (∇²_F Ψ − ∇_F C ∇_F Cᵀ)/C has the same modes with c = ψ/C, except 0 along ĝ (the
// scaling basis is ĝ and two unit vectors ⊥ ĝ).
// Where σᵢ + σⱼ < tet_twist_epsilon (a tet flattened onto a line, or inverted with σ₃ = −σ₂) R is
// not differentiable: the sum is floored at tet_twist_epsilon (a large negative, finite twist
// eigenvalue).
// C's kink at rest: below tet_rest_epsilon (constraints.hpp) the gradient is zero by convention,
// and ∇²_F C (whose eigenvalues grow as 1/C) is zero too, so G = −λ∇²C = 0 there; Ψ is smooth at
// rest, so H = ∇²Ψ/α̃ needs no convention (at F = R: twist 0, all others 1/α̃).
constexpr double tet_twist_epsilon = 1e-12;

struct ArapEigensystem {
  std::array<Eigen::Matrix3d, 9> mode;  // 0–2 scale (0 along ĝ), 3–5 twist (01, 02, 12), 6–8 flip
  Eigen::Matrix<double, 9, 1> psi;      // eigenvalues of ∇²_F Ψ
  Eigen::Matrix<double, 9, 1> c;        // eigenvalues of ∇²_F C (all 0 below tet_rest_epsilon)
  double C = 0;
};
ArapEigensystem arap_eigensystem(const Eigen::Matrix3d& F);
// The same from F's rotation-variant SVD (svd_rv) already at hand.
ArapEigensystem arap_eigensystem(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& sigma,
                                 const Eigen::Matrix3d& V);

// F = Ds·Dm⁻¹ of a tet, and ∂F/∂x: ∂F_ik/∂x_{a,i'} = δ_{ii'} B(a, k), B's rows 1–3 those of Dm⁻¹,
// row 0 minus their sum.
Eigen::Matrix3d tet_deformation_gradient(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                         const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv);
Eigen::Matrix<double, 4, 3> tet_shape_gradients(const Eigen::Matrix3d& Dm_inv);
// Σ_k μ_k (D q_k)(D q_k)ᵀ over the eigensystem's modes: a 9×9 F-space matrix mapped to x, made
// exactly symmetric.
Matrix12d tet_modes_to_x(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu,
                         const Eigen::Matrix<double, 4, 3>& B);
// Its diagonal alone (what §1.4's diagonal needs), without the 12×12 matrix.
Eigen::Matrix<double, 12, 1> tet_modes_diagonal(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu,
                                                const Eigen::Matrix<double, 4, 3>& B);
// Σ_k μ_k vec(Q_k) vec(Q_k)ᵀ: the same in F-space.
Matrix9d tet_modes_to_F(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu);

// The smallest displacement of the tet's particles (12, x0..x3) whose change of F is Q:
// δX = Q(BᵀB)⁻¹Bᵀ, so δX·B = Q and Σ_a δx_a = 0. Along it the curvature of Ψ is Q's own
// eigenvalue (δxᵀ∇²_xΨ δx = vec(Q)ᵀ∇²_FΨ vec(Q)): a twist mode with ψ < 0 is a direction of
// negative curvature of the element, in closed form.
Eigen::Matrix<double, 12, 1> tet_mode_displacement(const Eigen::Matrix3d& Q, const Eigen::Matrix<double, 4, 3>& B);

// ∇²C (12×12, x0..x3) and ∇²_F C (9×9).
Matrix12d tet_arap_hessian(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                           const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv);
// G = −λ∇²C and H = ∇²Ψ/α̃ = (∇C∇Cᵀ + C∇²C)/α̃, each projected in F-space by the closed form
// (eigenvalues −λc and ψ/α̃ through π), then mapped to x (Dᵀ(·)D keeps PSD).
Matrix12d tet_geometric_stiffness(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                  const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv, double lambda, Projection proj);
// tet_energy_hessian also gives C and ∇C (tet_arap_constraint's with rest_epsilon = 0, Newton's, from
// the same SVD) where asked, and
// `smallest`: min_k ψ_k/α̃, the smallest F-space eigenvalue of the exact H (negative: indefinite);
// `tolerance` as for the distance: proj applies only where min_k ψ_k < −tolerance.
// The diagonal of tet_geometric_stiffness.
Eigen::Matrix<double, 12, 1> tet_geometric_stiffness_diagonal(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                                              const Eigen::Vector3d& x2, const Eigen::Vector3d& x3,
                                                              const Eigen::Matrix3d& Dm_inv, double lambda, Projection proj);
Matrix12d tet_energy_hessian(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                             const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv, double alpha_tilde, Projection proj,
                             double* C = nullptr, std::array<Eigen::Vector3d, 4>* grad = nullptr, double* smallest = nullptr,
                             double tolerance = 0);
// The same from F = UΣVᵀ (svd_rv) already at hand: no decomposition (ElementHessians::evaluate keeps them).
Matrix12d tet_energy_hessian_from_svd(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& sigma,
                                      const Eigen::Matrix3d& V, const Eigen::Matrix3d& Dm_inv, double alpha_tilde,
                                      Projection proj, double* smallest = nullptr, double tolerance = 0);

}  // namespace xb
