// The node-block diagonal D of a block matrix (3×3 per particle on K, the QR block of each
// aggregate on coarse levels): D_I = A's (I, I) block. A Jacobi step with D⁻¹ instead of the
// scalar diagonal treats a particle's x, y, z together, which matters when a particle's own
// block is far from diagonal (stretched tets, cloth edges at an angle to the axes).
#pragma once

#include "../node_layout.hpp"
#include "../../../core/sparse.hpp"

#include <vector>

namespace xb::amg {

struct BlockOperator;

class BlockDiagonal {
 public:
  // A scalar layout gives 1×1 blocks. Throws xb::Error if a block is not positive definite.
  void build(const SparseMatrix& A, const NodeLayout& nodes);
  // y = D⁻¹ x and y = D x (y resized).
  void apply_inverse(const Vector& x, Vector& y) const;
  void apply(const Vector& x, Vector& y) const;
  int rows() const { return start_.empty() ? 0 : start_.back(); }
  int num_nodes() const { return static_cast<int>(start_.size()) - 1; }
  int node_begin(int I) const { return start_[I]; }
  int node_end(int I) const { return start_[I + 1]; }
  // Row-major b_I × b_I entry (r, s) of D_I⁻¹, local indices.
  double inverse(int I, int r, int s) const {
    return inv_[offset_[I] + r * (start_[I + 1] - start_[I]) + s];
  }
  // D_I⁻¹ and D_I, row-major b_I × b_I.
  const double* inverse_block(int I) const { return inv_.data() + offset_[I]; }
  const double* block(int I) const { return block_.data() + offset_[I]; }
  // The node starts, block offsets and row-major D_I⁻¹ blocks (DiagonalRelaxation's layout).
  void export_inverse(std::vector<int>& start, std::vector<long>& offset, std::vector<double>& inv) const {
    start = start_;
    offset = offset_;
    inv = inv_;
  }

 private:
  std::vector<int> start_;     // node rows, as NodeLayout::node_start
  std::vector<long> offset_;   // start of node I's block in block_ and inv_
  std::vector<double> block_, inv_;
};

// Upper estimate of λ_max(D⁻¹A) for the block D: Lanczos on D⁻¹A in the D inner product (where
// it is self-adjoint), largest Ritz value plus its residual bound — as estimate_lambda_max does for
// the scalar diagonal. v: start vector, updated (zero or wrong size: a seeded random one).
// blocks: A's node blocks for its products, or null.
double estimate_lambda_max(const SparseMatrix& A, const BlockDiagonal& D, Vector& v, int iterations, unsigned seed,
                           const BlockOperator* blocks = nullptr);

}  // namespace xb::amg
