#include "block_chebyshev.hpp"

#include "../../../core/error.hpp"

#include <cmath>

namespace xb::amg {

namespace {
class BlockDiagonalSmoother final : public Smoother {
 public:
  BlockDiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes)
      : opt_(opt), nodes_(nodes) {
    relax_.chebyshev = opt.kind == "block_chebyshev";
    relax_.sweeps = opt.sweeps;
    update(A, opt_.power_iterations);
  }
  std::string name() const override { return opt_.kind; }
  void refresh(const SparseMatrix& A) override { update(A, opt_.refresh_power_iterations); }
  double lambda_max() const override { return relax_.lambda; }
  bool block_diagonal() const override { return true; }
  const DiagonalRelaxation<double>* relaxation() const override { return &relax_; }
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    relax_.presmooth(A, b, x, x_zero);
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override { relax_.postsmooth(A, b, x); }

 private:
  void update(const SparseMatrix& A, int lanczos_steps) {
    D_.build(A, nodes_);
    relax_.lambda = estimate_lambda_max(A, D_, eigvec_, lanczos_steps, opt_.seed);
    if (!(relax_.lambda > 0) || !std::isfinite(relax_.lambda))
      throw Error("amg.smoother=" + opt_.kind + ": no positive spectral radius estimate on a level of " +
                  std::to_string(A.rows()) + " rows (matrix not positive definite?)");
    D_.export_inverse(relax_.node_start, relax_.offset, relax_.block_inv);
  }

  SmootherOptions opt_;
  NodeLayout nodes_;
  BlockDiagonal D_;
  DiagonalRelaxation<double> relax_;
  Vector eigvec_;
};
}  // namespace

std::unique_ptr<Smoother> make_block_diagonal_smoother(const SmootherOptions& opt, const SparseMatrix& A,
                                                       const NodeLayout& nodes) {
  return std::make_unique<BlockDiagonalSmoother>(opt, A, nodes);
}

}  // namespace xb::amg
