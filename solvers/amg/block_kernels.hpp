// The V-cycle's passes over a node-block CSR matrix (block_sparse.hpp: every row of a row node
// holds the same whole column nodes, so block (I, J) is a dense array inside the CSR values).
// Read by blocks, a row node's rows are swept together: one column node index per block instead of
// one column index per entry, x_J loaded once for all of node I's rows, and the 3×3 (K) and 6×6
// (rigid-mode coarse levels) blocks unrolled. The primal form's level matrices, P and R all have
// this form; the dual form's scalar levels keep the CSR kernels. Any precision S (the float
// V-cycle reads the float copies, whose values sit where the double ones do).
#pragma once

#include "block_sparse.hpp"

namespace xb::amg {

// A's node blocks as the kernels read them.
struct BlockOperator {
  BlockPattern pattern;
  int uniform_rows = 0, uniform_cols = 0;  // every row (column) node's size when all share it, else 0
  int max_row_length = 0;                  // the longest row of A (the gathered kernels' buffer)

  // False (and empty) when A is not node-block CSR in these layouts or a node holds more than
  // kMaxNodeSize unknowns.
  bool build(const SparseMatrix& A, const NodeLayout& row_nodes, const NodeLayout& col_nodes);
  bool empty() const { return pattern.ptr.empty(); }
  static constexpr int kMaxNodeSize = 64;
};

// r = b − A x.
template <class S>
void block_residual(const BlockOperator& op, const CsrOf<S>& A, const S* x, const S* b, S* r);
// y = A x (add: y += A x).
template <class S>
void block_multiply(const BlockOperator& op, const CsrOf<S>& A, const S* x, S* y, bool add);
// d = c1·d + c2·D⁻¹(b − A x), D⁻¹ node I's row-major block at block_inv[offset[I]] (c1 = 0: d is
// not read). The relaxation step of diagonal_relaxation.hpp by blocks.
template <class S>
void block_relax_step(const BlockOperator& op, const CsrOf<S>& A, const S* block_inv, const long* offset, const S* b,
                      const S* x, double c1, double c2, S* d);

}  // namespace xb::amg
