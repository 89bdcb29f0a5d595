// Level 0 of a block system without its numerically zero couplings (amg.drop_tolerance).
// K's pattern comes from the mesh (every pair of particles sharing a constraint), but a coupling
// can vanish in value: on the uniformly stretched tet-ARAP bar (bar_hang, prestretch 1.05) a tet's
// constraint gradient is zero at the corners whose barycentric gradient is orthogonal to the
// stretch, and 3/4 of K's off-diagonal blocks are below 1e-14 of their diagonals. Kept, such
// blocks count as couplings at θ = 0: aggregates grow across the bar's lines of real coupling,
// the smoothed P spreads over them and the Galerkin operators fill in (docs/mgpbd.md).
//
// A block (I, J), I ≠ J, with ‖A_IJ‖_F < tol·sqrt(‖A_II‖_F ‖A_JJ‖_F) is dropped and ‖A_IJ‖_F is
// added to every diagonal entry of node I. For a symmetric A the pair (I, J), (J, I) is dropped
// together, and [σI, −E; −Eᵀ, σI] ⪰ 0 for σ = ‖E‖_F ≥ ‖E‖₂, so A_F − A is positive
// semi-definite: A_F stays SPD (the V-cycle on it a valid CG preconditioner for A) whatever the
// values at a later refresh, when a dropped block may no longer be small.
#pragma once

#include "block_sparse.hpp"

#include <cmath>
#include <vector>

namespace xb::amg {

class ZeroBlockFilter {
 public:
  // A_F from A, read as node blocks of p (A's own pattern, square layout). False, and nothing
  // kept, when no block is below tol: the caller then uses A itself.
  bool build(const SparseMatrix& A, const BlockPattern& p, double tol);
  // A with the pattern it had in build(), new values: the same blocks dropped, lumps recomputed.
  // Returns whether every dropped block is still below tol: false once the state has moved on and
  // a dropped coupling is real (a hierarchy built on A_F is then stale; A_F is still above A).
  bool refresh(const SparseMatrix& A);
  const SparseMatrix& matrix() const { return F_; }
  long source_nonzeros() const { return source_nnz_; }
  int dropped_blocks() const { return static_cast<int>(drop_block_.size()); }

 private:
  double block_norm(const SparseMatrix& A, int I, int k) const;
  std::vector<double> diagonal_norms(const SparseMatrix& A) const;
  // Block k of row node I against tol (its norm is returned in `norm`).
  bool negligible(const SparseMatrix& A, int I, int k, const std::vector<double>& dnorm, double& norm) const {
    norm = block_norm(A, I, k);
    return norm < tol_ * std::sqrt(dnorm[I] * dnorm[p_.col[k]]);
  }
  BlockPattern p_;                 // A's blocks
  double tol_ = 0;
  std::vector<int> diag_block_;    // per node: its diagonal block's index in p_
  SparseMatrix F_;
  long source_nnz_ = 0;
  std::vector<int> source_;        // per entry of F_: its position in A's values
  std::vector<int> diag_;          // per row: its diagonal's position in F_
  std::vector<int> drop_ptr_;      // row node I: its dropped blocks [drop_ptr_[I], drop_ptr_[I+1])
  std::vector<int> drop_block_;    // per dropped block: its index in p_
};

}  // namespace xb::amg
