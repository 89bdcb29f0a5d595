// The dual system of XPBD (Eq. 8 of the supplemental):
//   A = ∇C M⁻¹ ∇Cᵀ + α̃,   b = −C − α̃λ,   Δx = M⁻¹ ∇Cᵀ Δλ.
// The sparsity pattern depends only on topology: two constraints couple when they share a
// particle that is not pinned (w = 0 couples nothing). It is built once; values are refilled
// in parallel per row each outer iteration, from a precomputed list of shared particles per
// non-zero.
#pragma once

#include "problem.hpp"
#include "../core/sparse.hpp"

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

  // out = M⁻¹ ∇Cᵀ y (per particle; pinned particles get 0).
  void apply_minv_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const;
  // out = ∇Cᵀ y (per particle, including pinned ones).
  void apply_gradT(const ConstraintState& s, const Eigen::VectorXd& y, Eigen::Matrix3Xd& out) const;

  // Particle p's constraints and the slot p holds in each.
  struct Incidence {
    int constraint;
    int slot;
  };
  const std::vector<int>& incidence_start() const { return inc_start_; }
  const std::vector<Incidence>& incidence() const { return inc_; }

 private:
  void build_incidence();  // particle → (constraint, slot)
  void build_pattern();    // A's pattern, the shared-particle pairs of each non-zero, the diagonals

  const Problem& prob_;
  SparseMatrix A_;
  std::vector<int> inc_start_;  // per particle, into inc_ (all particles, pinned included)
  std::vector<Incidence> inc_;
  std::vector<int> pair_start_;            // per non-zero, into pairs_
  std::vector<std::uint8_t> pairs_;        // (slot in row constraint) << 2 | (slot in column constraint)
  std::vector<int> diag_;                  // position of the diagonal in each row
};

}  // namespace xb
