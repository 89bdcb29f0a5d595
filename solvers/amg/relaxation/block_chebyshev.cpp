#include "block_chebyshev.hpp"

#include "../../../core/error.hpp"

#include <cmath>

namespace xb::amg {

namespace {
class BlockDiagonalSmoother final : public PolynomialSmoother {
 public:
  BlockDiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes,
                        const BlockOperator* blocks)
      : PolynomialSmoother(opt, opt.kind == "block_chebyshev"), nodes_(nodes) {
    relax_.blocks = blocks;
    update(A, opt_.power_iterations);
  }
  void refresh(const SparseMatrix& A) override { update(A, opt_.refresh_power_iterations); }
  const BlockDiagonal* block_diagonal() const override { return &D_; }

 private:
  void update(const SparseMatrix& A, int lanczos_steps) {
    D_.build(A, nodes_);
    relax_.lambda = estimate_lambda_max(A, D_, eigvec_, lanczos_steps, opt_.seed, relax_.blocks);
    check_lambda(A);
    D_.export_inverse(relax_.node_start, relax_.offset, relax_.block_inv);
  }

  NodeLayout nodes_;
  BlockDiagonal D_;
};
}  // namespace

std::unique_ptr<Smoother> make_block_diagonal_smoother(const SmootherOptions& opt, const SparseMatrix& A,
                                                       const NodeLayout& nodes, const BlockOperator* blocks) {
  return std::make_unique<BlockDiagonalSmoother>(opt, A, nodes, blocks);
}

}  // namespace xb::amg
