// The primal form of the XPBD linear step. For α̃ > 0 on every constraint, the dual system
//   (J M⁻¹ Jᵀ + α̃) Δλ = b                       (J = ∇C, one row per constraint)
// is exactly equivalent to
//   K Δx = f,   K = M + Jᵀ α̃⁻¹ J,   f = Jᵀ α̃⁻¹ b,   then   Δλ = α̃⁻¹ (b − J Δx),
// over the free particles (pinned ones, w = 0, have no unknowns). For an approximate Δx with
// primal residual r_K = f − KΔx, the recovered Δλ has the dual residual b − AΔλ = −J M⁻¹ r_K,
// so both forms are judged by one (dual) criterion at the cost of one product with J.
// K is stored node-major, 3 rows per free particle (block size 3); its pattern (two particles
// couple when they share a constraint) is built once, values are refilled per outer iteration.
// Its near-kernel is the 6 rigid-body motions (rigid_modes()).
#pragma once

#include "../core/sparse.hpp"
#include "element_hessians.hpp"

#include <Eigen/Dense>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace xb {

struct Problem;

// What the assembly of either form needs besides the gradients: each constraint's particles
// (−1 padded) and the particles' inverse masses (0 = pinned).
struct ConstraintGraph {
  std::vector<std::array<int, 4>> particles;
  Eigen::VectorXd w;
  int num_constraints() const { return static_cast<int>(particles.size()); }
  int num_particles() const { return static_cast<int>(w.size()); }
};
ConstraintGraph constraint_graph(const Problem& prob);

// Per constraint: ∂C/∂x of each of its (up to 4) particles, zero-padded.
using Gradients = std::vector<std::array<Eigen::Vector3d, 4>>;

// The forms of the linear step a run may ask for (the `form` key, --form): dual, primal, auto.
const std::vector<std::string>& form_choices();
// Throws xb::Error "WHERE: unknown form 'FORM' (valid: dual, primal, auto)" for a form not among them.
void check_form(const std::string& form, const std::string& where);

// "dual" or "primal" for a requested form (dual | primal | auto): auto is primal when every
// α̃ > 0. Throws xb::Error for primal with a constraint of zero compliance.
std::string resolve_form(const std::string& requested, const Eigen::VectorXd& alpha_tilde);

class PrimalSystem {
 public:
  explicit PrimalSystem(ConstraintGraph graph);

  const SparseMatrix& K() const { return K_; }
  int rows() const { return static_cast<int>(K_.rows()); }
  // Free particle of dof block i (rows 3i, 3i+1, 3i+2).
  const std::vector<int>& free_particles() const { return free_; }
  const ConstraintGraph& graph() const { return graph_; }

  // K's values: M + Σ_j g_j g_jᵀ / α̃_j on the blocks of shared free particles. Throws xb::Error
  // if some α̃ ≤ 0 (the primal form does not exist there).
  void fill(const Gradients& grad, const Eigen::VectorXd& alpha_tilde);
  // The top-left block M̃ in place of M (problems/element_hessians.hpp; the pattern is the same):
  // K = M + K̃_d + Jᵀα̃⁻¹J, kd per particle (3 × all particles, as ElementHessians fills it).
  void fill_with_diagonal(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& kd);
  // K = M + Σ_j G_j + Jᵀα̃⁻¹J, G_j the (projected) geometric stiffness blocks, each exactly
  // symmetric (as ElementHessians makes them: K's blocks (p, q) and (q, p) are then exact transposes).
  void fill_with_blocks(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const ElementMatrices& G);
  // Newton on E: K = M + Σ_j H_j = Δt²∇²E, H_j the (projected) element Hessians of ½C_j²/α̃_j,
  // which hold the Gauss–Newton part already (no Jᵀα̃⁻¹J is added).
  void fill_energy_hessian(const ElementMatrices& H);
  // Holds the listed dofs (K's row numbers) in the step: their rows and columns become zero but
  // for the diagonal, which is kept, so a zero right-hand side there gives Δx = 0 (the active
  // bounds of contact, harness/sim/plane_bounds.hpp). K stays SPD where it was. After a fill.
  void fix_dofs(const std::vector<int>& dofs);
  // f = Jᵀ α̃⁻¹ b.
  void rhs(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Vector& b, Vector& f) const;
  // Δλ = α̃⁻¹ (b − J Δx).
  void recover(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Vector& b, const Vector& dx,
               Vector& dlambda) const;
  // The dual residual b − AΔλ of the recovered Δλ, from the primal residual: −J M⁻¹ r_K.
  void dual_residual(const Gradients& grad, const Vector& r_K, Vector& out) const;
  // The same with M̃ = M + K̃_d: −J M̃⁻¹ r_K, w_dof per-dof inverse masses (shifted_inverse_masses).
  void dual_residual(const Gradients& grad, const Vector& r_K, const Eigen::Matrix3Xd& w_dof, Vector& out) const;
  // g = M(x − x̃) − Jᵀλ on the free particles' dof blocks (the KKT primal residual, Eq. 4).
  void primal_residual(const Gradients& grad, const Eigen::VectorXd& lambda, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& x_pred, Vector& g) const;
  // Δt²∇E = M(x − x̃) + Jᵀα̃⁻¹C, i.e. g at λ = −α̃⁻¹C (Eq. 14 times Δt²); grad and C at x.
  void energy_gradient(const Gradients& grad, const Eigen::VectorXd& C, const Eigen::VectorXd& alpha_tilde,
                       const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, Vector& out) const;
  // out = J v (one entry per constraint; v has one 3-block per free particle).
  void apply_J(const Gradients& grad, const Vector& v, Vector& out) const;
  // out = Jᵀ y (one 3-block per free particle).
  void apply_JT(const Gradients& grad, const Eigen::VectorXd& y, Vector& out) const;
  // The 6 rigid-body modes at positions x (all particles): columns 0–2 translations along x, y, z,
  // columns 3–5 rotations e_k × (p − centroid of the free particles).
  Eigen::MatrixXd rigid_modes(const Eigen::Matrix3Xd& x) const;

 private:
  void build_incidence();  // free particles, their dof blocks, free particle → (constraint, slot)
  void build_pattern();    // K's blocks and the terms of each, then build_csr()
  void build_csr();        // K's scalar CSR pattern from its blocks (values zero)
  void set_inverse_alpha(const Eigen::VectorXd& alpha_tilde);  // inv_alpha_, refusing α̃ ≤ 0
  // K's values: M (+ kd on the diagonal) (+ Jᵀα̃⁻¹J if kGaussNewton) (+ Σ blocks if kBlocks).
  template <bool kGaussNewton, bool kBlocks>
  void fill_values(const Gradients* grad, const Eigen::Matrix3Xd* kd, const ElementMatrices* blocks);
  // out = M(x − x̃) − Jᵀy with y_j = ys(j), on the free dof blocks.
  template <class Y>
  void inertia_minus_JT(const Gradients& grad, Y&& ys, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                        Vector& out) const;
  // out = sign · J (M⁻¹ if times_minv) v.
  void apply_J(const Gradients& grad, const Vector& v, double sign, bool times_minv, Vector& out) const;

  ConstraintGraph graph_;
  std::vector<int> free_;            // dof block → particle
  std::vector<int> block_of_;        // particle → dof block, −1 if pinned
  std::vector<int> inc_start_;       // per dof block, into inc_
  std::vector<int> inc_;             // (constraint << 2 | slot) of the free particle's constraints
  SparseMatrix K_;
  // Per block of K (node row p, node column q, in row order): the constraints they share, as
  // (constraint << 4 | slot_p << 2 | slot_q), from term_start_[blk] to term_start_[blk + 1].
  std::vector<int> block_start_;     // per node row, its first block
  std::vector<int> block_col_;       // per block, its node column
  std::vector<int> term_start_;
  std::vector<std::int64_t> terms_;
  Eigen::VectorXd inv_alpha_;        // 1/α̃ of the last fill
};

}  // namespace xb
