// Node-block products for block levels (the primal form's K and its smoothed aggregation).
// A CSR matrix is seen as node blocks when every row of a row node holds the same columns, whole
// column nodes in increasing order: block (I, J) is then a dense b_I × b_J row-major array inside
// the CSR values, with the row length as its stride. K (dense 3×3 blocks), the tentative P (a dense
// Q_a row block per particle) and every product of such matrices have this form, so the CSR that
// the V-cycle runs on is the block storage itself: no copy, no explicit zeros beyond the scalar
// product's (its pattern is the same), and the index work is per block instead of per entry.
// Products sum in the scalar spgemm's order, so their values are the same to round-off.
#pragma once

#include "node_layout.hpp"
#include "../../core/sparse.hpp"

#include <vector>

namespace xb::amg {

struct BlockPattern {
  std::vector<int> row_start, col_start;  // the row and column node layouts
  std::vector<int> ptr;                   // row node I: its blocks [ptr[I], ptr[I+1])
  std::vector<int> col;                   // per block: its column node J
  std::vector<int> offset;                // per block: position of its first entry within a row of I

  // A as node blocks of these layouts; false when a layout is scalar or does not fit A, or a
  // row node's rows differ in their columns or hold part of a column node.
  bool build(const SparseMatrix& A, const NodeLayout& row_nodes, const NodeLayout& col_nodes);
  int row_nodes() const { return static_cast<int>(row_start.size()) - 1; }
  int rows(int I) const { return row_start[I + 1] - row_start[I]; }
  int cols(int J) const { return col_start[J + 1] - col_start[J]; }
};

// C = A·B's pattern: C's CSR with its columns (values zero) and its block pattern. Throws
// xb::Error if A's column layout is not B's row layout.
void block_product_pattern(const BlockPattern& pa, const BlockPattern& pb, SparseMatrix& C, BlockPattern& pc);

// C = A·B into the pattern block_product_pattern made (also the values-only refresh). With mirror
// (block_mirror_map(pc)), C is known to be symmetric (Pᵀ·(A P) of a symmetric A): only its blocks
// on and above the diagonal are computed, those below copied from them transposed — half the
// work of the product, and a C that is exactly symmetric.
void block_product_values(const SparseMatrix& A, const BlockPattern& pa, const SparseMatrix& B, const BlockPattern& pb,
                          SparseMatrix& C, const BlockPattern& pc, const std::vector<int>* mirror = nullptr);
// Per block (I, J) of a square block pattern with J < I: the index of block (J, I) (−1 for J ≥ I).
// Throws xb::Error if the layout is not square or some block has no mirror (not symmetric).
std::vector<int> block_mirror_map(const BlockPattern& pc);

// C = A·B, pattern and values.
SparseMatrix block_product(const SparseMatrix& A, const BlockPattern& pa, const SparseMatrix& B, const BlockPattern& pb,
                           BlockPattern& pc);

}  // namespace xb::amg
