// Symmetric multicolour block Gauss–Seidel on the nodes of a block system (3×3 particle blocks
// on K, an aggregate's kept QR columns on coarse levels; 1×1 on a scalar layout). Each node's
// unknowns are solved together with the inverse of its diagonal block (factorised once per setup
// or refresh): the coupled x, y, z of a stretched tet are relaxed as one, which scalar GS and
// scalar-diagonal Chebyshev treat as three weakly linked rows. Nodes of one colour share no
// stored coupling, so they are updated in parallel; the V-cycle sweeps forward before and
// backward after, so the post-smoother is the A-adjoint of the pre-smoother (symmetric for CG).
#pragma once

#include "block_diagonal.hpp"
#include "../../coloring.hpp"
#include "smoother.hpp"

namespace xb::amg {

// Greedy colouring of the node graph (node I and J differ when any entry of block (I, J) is
// stored); a scalar layout colours the rows.
Coloring node_coloring(const SparseMatrix& A, const NodeLayout& nodes);

// One sweep on A x = b: x_I ← x_I + D_I⁻¹ (b_I − (A x)_I) node by node, colours in order
// (forward) or reversed (backward). `coloring` colours D's nodes.
void block_gs_sweep(const SparseMatrix& A, const BlockDiagonal& D, const Coloring& coloring, const Vector& b,
                    Vector& x, bool forward);

class BlockGaussSeidelSmoother final : public Smoother {
 public:
  // Throws xb::Error if a diagonal block is not positive definite.
  BlockGaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes);
  std::string name() const override { return "block_gs"; }
  bool symmetric_from_zero() const override { return false; }
  void refresh(const SparseMatrix& A) override { D_.build(A, nodes_); }  // colouring: pattern only
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override;
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override;

 private:
  SmootherOptions opt_;
  NodeLayout nodes_;
  Coloring coloring_;
  BlockDiagonal D_;
};

}  // namespace xb::amg
