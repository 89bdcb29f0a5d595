// The per-constraint second-order blocks of a whole Problem, filled in parallel every outer
// iteration into storage allocated once (problems/constraint_hessian.hpp has the single-constraint
// formulas and the sign convention: G_j = −λ_j∇²C_j, H_j = (∇C_j∇C_jᵀ + C_j∇²C_j)/α̃_j).
// They enter the linear step through PrimalSystem (fill_with_diagonal, fill_with_blocks,
// fill_energy_hessian) and, for the diagonal, DualSystem's per-dof inverse masses:
//   geometric_stiffness = diagonal   K̃_d = max(0, diag of Σ_j G_j's particle blocks) per dof;
//                                    dual A = J(M + K̃_d)⁻¹Jᵀ + α̃, primal K = M + K̃_d + Jᵀα̃⁻¹J
//   geometric_stiffness = full       primal K = M + Σ_j π(G_j) + Jᵀα̃⁻¹J
//   Newton on E                      K = M + Σ_j π(H_j) = Δt²∇²E (projected), gradient Δt²∇E =
//                                    PrimalSystem::energy_gradient, E = incremental_energy
//                                    (harness/sim/residual_energy.hpp; Δt²E = h²·it).
// With M̃ = M + K̃_d (or M + Σ G_j) in the top-left block the recovery is unchanged:
// M̃Δx − JᵀΔλ = 0 and JΔx + α̃Δλ = b give Δλ = α̃⁻¹(b − JΔx) and (M̃ + Jᵀα̃⁻¹J)Δx = Jᵀα̃⁻¹b; only
// Δx = M̃⁻¹JᵀΔλ and the dual residual −JM̃⁻¹r_K use M̃ in place of M.
#pragma once

#include "constraint_hessian.hpp"
#include "problem.hpp"

#include <Eigen/Dense>

#include <vector>

namespace xb {

// One symmetric 3k × 3k matrix per constraint in its particle order (k = 2 for a distance, 4 for a
// tet; distances first, as Problem numbers them), stored flat and column-major: 36 + 144 doubles,
// not a 12×12 for every edge of a cloth. Blocks of pinned particles are kept; the assembly skips them.
class ElementMatrices {
 public:
  // Sizes the storage (no allocation when the sizes are unchanged).
  void resize(int num_distance, int num_tets);
  int size() const { return nd_ + nt_; }
  int slots(int j) const { return j < nd_ ? 2 : 4; }
  Eigen::Map<Eigen::MatrixXd> matrix(int j) { return Eigen::Map<Eigen::MatrixXd>(data(j), 3 * slots(j), 3 * slots(j)); }
  Eigen::Map<const Eigen::MatrixXd> matrix(int j) const {
    return Eigen::Map<const Eigen::MatrixXd>(data(j), 3 * slots(j), 3 * slots(j));
  }
  // Block (a, b) of constraint j: the 3×3 coupling of its particles a and b.
  Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>> block(int j, int a, int b) const {
    const int n = 3 * slots(j);
    return Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>>(data(j) + 3L * b * n + 3 * a, Eigen::OuterStride<>(n));
  }
  const double* data(int j) const { return values_.data() + offset(j); }
  double* data(int j) { return values_.data() + offset(j); }

 private:
  long offset(int j) const { return j < nd_ ? 36L * j : 36L * nd_ + 144L * (j - nd_); }
  int nd_ = 0, nt_ = 0;
  std::vector<double> values_;
};

// How fill_energy_hessian projects the elements: by `base`, but only those whose smallest exact
// eigenvalue is below −tolerance in units of their own stiffness 1/α̃_j (ψ < −tolerance for a tet;
// 0: every indefinite element). The progressive strategy (harness/sim/hessian_projection.hpp)
// leaves the mildly indefinite elements exact this way.
struct ElementProjection {
  Projection base = Projection::clamp;
  double tolerance = 0;
};

class ElementHessians {
 public:
  // Keeps a reference to prob (its constraints and masses; positions are passed in).
  explicit ElementHessians(const Problem& prob);

  // blocks().matrix(j) = π(G_j) = π(−λ_j∇²C_j(x)).
  void fill_geometric_stiffness(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda, Projection proj);
  // blocks().matrix(j) = π(H_j) = π((∇C_j∇C_jᵀ + C_j∇²C_j)/α̃_j) at x. Throws xb::Error if some α̃ ≤ 0.
  // With `state`, also evaluate_constraints(prob, x, *state) from the same SVDs (identical values),
  // so a Newton iteration needs one pass over the constraints, not two.
  void fill_energy_hessian(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, Projection proj,
                           ConstraintState* state = nullptr) {
    fill_energy_hessian(x, alpha_tilde, ElementProjection{proj, 0}, state);
  }
  // reuse_svd: x is the point of the last evaluate(), whose tet SVDs are used (no decomposition).
  void fill_energy_hessian(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, const ElementProjection& proj,
                           ConstraintState* state = nullptr, bool reuse_svd = false);
  // Newton's evaluation at x (problems/constraints.hpp with rest_epsilon = 0): every constraint's C
  // and ∇C into `state`, each tet's SVD kept for the next fill_energy_hessian(…, reuse_svd = true)
  // at the same x, so an iteration decomposes each element once.
  void evaluate(const Eigen::Matrix3Xd& x, ConstraintState& state);
  const ElementMatrices& blocks() const { return blocks_; }
  // After fill_energy_hessian, per constraint: the smallest eigenvalue of its exact (unprojected)
  // H_j in the closed-form eigenbasis (problems/constraint_hessian.hpp); negative: indefinite.
  const std::vector<double>& smallest_eigenvalues() const { return smallest_; }
  // Constraint j's direction of its exact Hessian's smallest eigenvalue, as a displacement of its
  // particles (12: 4 slots of 3; a distance fills slots 0–1): a tet's lowest ARAP mode through
  // tet_mode_displacement (from the SVD of the last evaluate() at x), a distance's transverse
  // direction. Returns the curvature δxᵀH_jδx (< 0: a direction of negative curvature).
  double lowest_mode(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, int j,
                     Eigen::Matrix<double, 12, 1>& dx) const;
  // Of the last evaluate(): tets with det F < 0 and the smallest σ₂ + σ₃ among them (the ARAP
  // energy's ridge is σ₂ + σ₃ = 0, where its rotation is not differentiable; +inf where none).
  int inverted_tets(double& smallest_twist_sum) const;
  // Of the last fill: elements with a negative eigenvalue, and those among them it projected.
  int indefinite_elements() const { return indefinite_; }
  int projected_elements() const { return projected_; }

  // §1.4's diagonal: kd(:, p) = max(0, the diagonal of Σ_j π(G_j)'s (p, p) block) per dof, for every
  // particle (pinned ones 0). proj = none sums the exact blocks and clamps the sums; clamp/abs sum
  // projected blocks (already ≥ 0). Does not touch blocks().
  void geometric_stiffness_diagonal(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda, Eigen::Matrix3Xd& kd,
                                    Projection proj = Projection::none);

 private:
  const Problem& prob_;
  ElementMatrices blocks_;
  std::vector<std::array<Eigen::Vector3d, 4>> diag_;  // per constraint and slot: its block's diagonal
  std::vector<int> inc_start_, inc_;                   // particle → (constraint << 2 | slot)
  std::vector<double> smallest_;
  int indefinite_ = 0, projected_ = 0;
  struct Svd {
    Eigen::Matrix3d U, V;
    Eigen::Vector3d sigma;
  };
  std::vector<Svd> svd_;  // per tet, of the last evaluate()
};

// Per-dof inverse masses of M̃ = M + K̃_d: w_dof(d, p) = 1/(1/w_p + kd(d, p)), 0 where w_p = 0.
void shifted_inverse_masses(const Eigen::VectorXd& w, const Eigen::Matrix3Xd& kd, Eigen::Matrix3Xd& w_dof);

}  // namespace xb
