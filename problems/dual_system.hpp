// The dual system of XPBD (Eq. 8 of the supplemental):
//   A = ∇C M⁻¹ ∇Cᵀ + α̃,   b = −C − α̃λ,   Δx = M⁻¹ ∇Cᵀ Δλ.
// The sparsity pattern depends only on topology: two constraints couple when they share a
// particle that is not pinned (w = 0 couples nothing). It is built once, with a fill recipe:
// row i gets w_p gᵢ,ₚ·gⱼ,ₚ from every constraint j at each of its free particles p, and the
// recipe holds, per such term, the position of A_ij. Each fill first copies the gradients into
// particle order (each particle's constraints contiguous, so a row reads four short runs instead
// of gathering a gradient per non-zero), then writes each row in one pass (parallel over rows).
#pragma once

#include "problem.hpp"
#include "../core/sparse.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace xb {

class DualSystem {
 public:
  explicit DualSystem(const Problem& prob);

  const SparseMatrix& A() const { return A_; }
  int rows() const { return static_cast<int>(A_.rows()); }

  // A's values from the gradients in `s` and α̃ (diagonal Σ w|g|² + α̃, off-diagonal
  // Σ over shared particles w·(gᵢ·gⱼ)). The pattern is unchanged.
  void fill(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde);
  // The same with per-dof inverse masses: A = J M̃⁻¹ Jᵀ + α̃ for a diagonal M̃ = M + K̃_d (the
  // geometric stiffness diagonal, problems/element_hessians.hpp), w_dof 3 × all particles
  // (pinned ones ignored: they couple nothing whatever w_dof holds).
  void fill(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& w_dof);

  // out = M⁻¹ ∇Cᵀ y (per particle; pinned particles get 0).
  void apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const;
  // out = M̃⁻¹ ∇Cᵀ y with per-dof inverse masses (pinned particles get 0).
  void apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, const Eigen::Matrix3Xd& w_dof,
                        Eigen::Matrix3Xd& out) const;
  // out = ∇Cᵀ y (per particle, including pinned ones).
  void apply_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const;
  // The same with every gradient entry by its absolute value (y ≥ 0: a bound on |Jᵀy|'s terms).
  void apply_abs_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const;

  // Particle p's constraints and the slot p holds in each.
  struct Incidence {
    int constraint;
    int slot;
  };
  const std::vector<int>& incidence_start() const { return inc_start_; }
  const std::vector<Incidence>& incidence() const { return inc_; }

 private:
  void build_incidence();  // particle → (constraint, slot)
  void build_pattern();    // A's pattern, the diagonals, the fill recipe
  void prefetch_row(int i) const;
  // A's values with the product of particle p's gradients ga, gb weighted by dot(p, ga, gb).
  template <class Dot>
  void fill_values(const ConstraintState& s, const Eigen::VectorXd& alpha_tilde, Dot&& dot);
  // out = Σ op(∇C)ᵀ y per particle (apply_gradT, apply_abs_gradT).
  template <class Op>
  void gather_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out, Op op) const;

  const Problem& prob_;
  SparseMatrix A_;
  std::vector<std::array<int, 4>> particles_;  // per constraint, as prob.constraint_particles()
  std::vector<int> inc_start_;  // per particle, into inc_ (all particles, pinned included)
  std::vector<Incidence> inc_;
  std::vector<int> diag_;                  // position of the diagonal in each row
  // The fill recipe. Row i's terms, from term_start_[i]: for each free slot a of row i (bit a of
  // free_slots_[i]) with particle p, one per incidence k of p, at position term_pos_ of A_ij.
  std::vector<std::uint8_t> free_slots_;
  std::vector<int> term_start_;
  std::vector<int> term_pos_;              // relative to the row's first non-zero
  std::vector<int> slot_inc_;              // per constraint j and slot a: its incidence k, −1 if none
  std::vector<Eigen::Vector3d> grad_at_;   // per incidence k: the gradient of its constraint at its particle
};

}  // namespace xb
