// Galerkin coarse operators A_c = Pᵀ A P (Eq. 27, R = Pᵀ).
//  General path: two parallel row-wise (Gustavson) sparse products, R·(A·P); any P. On block
//    levels (the primal form) the same products by node blocks (block_sparse.hpp).
//  One-candidate path: when P has at most one entry per row (p_i in column agg(i)),
//    A_c[agg(i), agg(j)] = Σ p_i A_ij p_j, a weighted sum over aggregates. build() finds A_c's
//    pattern and, per coarse non-zero, the list of fine non-zeros that add into it with their
//    weights p_i p_j; refresh() is then one parallel gather pass over A's values (no atomics).
#pragma once

#include "../../core/sparse.hpp"
#include "block_sparse.hpp"

#include <vector>

namespace xb::amg {

// C = A·B, parallel over rows, sorted columns; structural zeros are kept (no value dropping),
// so the pattern depends only on the patterns of A and B.
SparseMatrix spgemm(const SparseMatrix& A, const SparseMatrix& B);

// Pᵀ A P with R = Pᵀ given (the tentative prolongator builds both).
SparseMatrix galerkin_product(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P);

// C = A·B into C's existing pattern (that of spgemm(A, B) for the same patterns): the numeric
// pass alone, no counting and no sorting. Gives bit-identical values to spgemm.
void spgemm_values(const SparseMatrix& A, const SparseMatrix& B, SparseMatrix& C);

// The general Galerkin product with its pattern cached: build() runs R·(A·P) and keeps A·P;
// refresh() (A's values changed, same pattern; R, P unchanged) recomputes both products' values
// only — the lazy setup of a hierarchy whose P has several entries per row. Given block layouts
// (fine: A's nodes, coarse: P's column nodes) both products run by node blocks
// (block_sparse.hpp) when the matrices allow it: the same A_c, less index work.
class GalerkinProduct {
 public:
  void build(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac,
             const NodeLayout& fine = {}, const NodeLayout& coarse = {});
  // The same by node blocks, with the block patterns of R, A and P already built (the V-cycle's
  // BlockOperators hold them); kept for refresh().
  // symmetric: A is symmetric and R = Pᵀ, so A_c is computed on and above its block diagonal
  // and mirrored (block_product_values; the hierarchy's case).
  void build(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac, BlockPattern pr,
             BlockPattern pa, BlockPattern pp, bool symmetric = false);
  void refresh(const SparseMatrix& R, const SparseMatrix& A, const SparseMatrix& P, SparseMatrix& Ac);
  bool by_blocks() const { return by_blocks_; }

 private:
  SparseMatrix AP_;
  bool by_blocks_ = false;
  BlockPattern r_, a_, p_, ap_, ac_;  // the block patterns of R, A, P, A·P and A_c
  std::vector<int> mirror_;           // symmetric: A_c's block mirror map (empty: the full product)
};

class AggregateGalerkin {
 public:
  // P: n × n_c with ≤ 1 entry per row; R = Pᵀ. Sets A_c (pattern and values) and the map.
  // Throws xb::Error if a row of P has more than one entry.
  void build(const SparseMatrix& A, const SparseMatrix& P, const SparseMatrix& R, SparseMatrix& Ac);
  // A has the pattern it had in build(); rewrites A_c's values only.
  void refresh(const SparseMatrix& A, SparseMatrix& Ac) const;
  bool built() const { return !slot_start_.empty(); }

 private:
  std::vector<int> slot_start_;  // per coarse non-zero: its contributions [slot_start_[s], slot_start_[s+1])
  std::vector<int> src_;         // index of the fine non-zero A_ij
  std::vector<double> weight_;   // p_i p_j
  long fine_nnz_ = 0;
};

}  // namespace xb::amg
