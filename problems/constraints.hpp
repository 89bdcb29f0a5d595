// Constraint types: per type a batch in struct-of-arrays form and a pure function for one
// constraint's value and gradient. Gradients are checked against finite differences in tests.
#pragma once

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace xb {

// Distance: C = |p − q| − l₀, ∇_p C = n = (p − q)/|p − q|, ∇_q C = −n.
// At |p − q| = 0 the direction is undefined: the gradient is zero (the constraint exerts no
// force along an undefined direction) and C = −l₀.
struct DistanceBatch {
  std::vector<std::array<int, 2>> idx;
  std::vector<double> rest_length;
  std::vector<double> compliance;  // α, m/N
  size_t size() const { return idx.size(); }
};
double distance_constraint(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double rest,
                           Eigen::Vector3d* grad_p, Eigen::Vector3d* grad_q);

// Tet ARAP (the paper's): F = Ds·Dm⁻¹, Ds = [x1−x0, x2−x0, x3−x0], SVD F = UΣVᵀ with the
// rotation-variant convention (det U = det V = 1, σ₃ may be negative for inverted tets),
// C = sqrt(Σ(σᵢ − 1)²) = ‖F − R‖_F with R = UVᵀ the closest rotation, and
// ∂C/∂F = (F − R)/C (envelope theorem: R maximises tr(RᵀF)), ∇_{x1,x2,x3} C = columns of
// (∂C/∂F)·Dm⁻ᵀ, ∇_{x0} C = −their sum. α = 1/(μ·V_rest).
//
// At C → 0 the gradient (F − R)/C has unit norm but no defined direction (C is a norm, with
// a kink at rest). We do not keep a stale gradient: below tet_rest_epsilon the gradient is
// zero, so the constraint's row of A is α̃ alone and it exerts no force — which is its
// physical force λ∇C → 0 at rest. At compliance 0 such a row is singular, and a global
// solver reports it (status breakdown).
// Newton on E (harness/sim/newton.hpp) needs C∇C = (F − R)·Dm⁻ᵀ-columns, the gradient of ½C², which
// has no kink: it evaluates with rest_epsilon = 0 (∇C zero only at C = 0 exactly), since the cut
// at 1e-9 leaves out up to 1e-9·|∇C|/α̃ per element and stalls ‖∇E‖ there (cantilever: 2.5e-7).
constexpr double tet_rest_epsilon = 1e-9;

struct TetArapBatch {
  std::vector<std::array<int, 4>> idx;
  std::vector<Eigen::Matrix3d> Dm_inv;
  std::vector<double> rest_volume;  // m³
  std::vector<double> compliance;   // α = 1/(μ V_rest)
  size_t size() const { return idx.size(); }
};
double tet_arap_constraint(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                           const Eigen::Vector3d& x2, const Eigen::Vector3d& x3,
                           const Eigen::Matrix3d& Dm_inv, std::array<Eigen::Vector3d, 4>* grad, double rest_epsilon = tet_rest_epsilon);

// Rotation-variant SVD of a 3×3 matrix: F = U diag(sigma) Vᵀ with U, V proper rotations.
void svd_rv(const Eigen::Matrix3d& F, Eigen::Matrix3d& U, Eigen::Vector3d& sigma, Eigen::Matrix3d& V);
// The tet's C and (if grad) ∇C from F = UΣVᵀ already at hand (tet_arap_constraint's formula).
double tet_arap_from_svd(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& sigma,
                         const Eigen::Matrix3d& V, const Eigen::Matrix3d& Dm_inv, std::array<Eigen::Vector3d, 4>* grad,
                         double rest_epsilon = tet_rest_epsilon);

}  // namespace xb
