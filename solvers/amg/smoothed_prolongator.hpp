// The smoothed prolongator of smoothed aggregation (Vaněk, Mandel, Brezina):
//   P = (I − ω D⁻¹A) T,   ω = 4 / (3 λ_max(D⁻¹A)),
// one damped-Jacobi step applied to the tentative P's columns. It lowers the energy of the coarse
// basis functions, which is what lets aggregation reach textbook rates on elasticity-like
// matrices (the primal form K). Since P·B_c = (I − ωD⁻¹A)B, near-kernel candidates are kept as
// well as A keeps them. D is A's diagonal (scalar) or its node blocks (block: D⁻¹ applied per
// node, λ_max(D⁻¹A) estimated on the symmetric L⁻¹AL⁻ᵀ with D_I = L_I L_Iᵀ).
#pragma once

#include "block_sparse.hpp"
#include "nodal.hpp"
#include "relaxation/block_diagonal.hpp"
#include "tentative.hpp"

namespace xb::amg {

enum class JacobiDiagonal { Scalar, Block };

struct SmoothedProlongator {
  SparseMatrix P, R;   // R = Pᵀ
  double omega = 0;    // the damping used
  double lambda = 0;   // the λ_max(D⁻¹A) estimate
};

// What the level's smoother already holds for A, reused instead of computed again (each optional).
struct ProlongatorReuse {
  double lambda = 0;                        // > 0: λ_max(D⁻¹A) for this D
  const BlockDiagonal* D = nullptr;         // A's node-block diagonal (JacobiDiagonal::Block)
  const BlockPattern* A_pattern = nullptr;  // A's node blocks in `nodes`
};

// A: SPD. T: the tentative prolongator. `nodes` is needed for the block diagonal (a scalar
// layout makes Block the same as Scalar). Lanczos steps and seed as for the smoothers.
// coarse_nodes: T's column nodes (Tentative::col_start); with block `nodes` the products run by
// node blocks (block_sparse.hpp), giving the same P and R.
// Throws xb::Error if A's diagonal (blocks) is not positive definite.
SmoothedProlongator smooth_prolongator(const SparseMatrix& A, const SparseMatrix& T, JacobiDiagonal diag,
                                       const NodeLayout& nodes, int lanczos_steps, unsigned seed,
                                       const NodeLayout& coarse_nodes = {}, const ProlongatorReuse& reuse = {});

// Filtered prolongator (amg.prolongator_drop_tolerance, as ML/MueLu drop small entries of the
// smoothed P): drops from P every node block (fine node I × coarse node J; with a scalar layout,
// or P not node-block CSR in these layouts, every entry) whose Frobenius norm is below
// tol · the largest of its row node (row). The largest is always kept, so no row empties. Returns
// the number of entries dropped (P is unchanged when none is).
long drop_small_blocks(SparseMatrix& P, const NodeLayout& fine, const NodeLayout& coarse, double tol);

// B = Aᵀ (parallel over A's columns is not needed: a counting sort, O(nnz)).
SparseMatrix transpose(const SparseMatrix& A);

}  // namespace xb::amg
