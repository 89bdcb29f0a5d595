#include "block_chebyshev.hpp"

#include "../../../core/error.hpp"

#include <cmath>

namespace xb::amg {

namespace {
class BlockDiagonalSmoother final : public Smoother {
 public:
  BlockDiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes)
      : opt_(opt), nodes_(nodes), chebyshev_(opt.kind == "block_chebyshev") {
    update(A, opt_.power_iterations);
  }
  std::string name() const override { return opt_.kind; }
  void refresh(const SparseMatrix& A) override { update(A, opt_.refresh_power_iterations); }
  double lambda_max() const override { return lambda_; }
  bool block_diagonal() const override { return true; }
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    for (int s = 0; s < opt_.sweeps; ++s) {
      const bool zero = x_zero && s == 0;
      if (chebyshev_) {
        chebyshev_iteration(
            lambda_, b.size(), x, zero, r_, d_, [&](Vector& r) { scaled_residual(A, b, x, r); },
            [&](Vector& r) { D_.apply_inverse(b, r); });
      } else if (zero) {
        D_.apply_inverse(b, x);
        x /= lambda_;
      } else {
        scaled_residual(A, b, x, r_);
        x += r_ / lambda_;
      }
    }
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override { presmooth(A, b, x, false); }

 private:
  void update(const SparseMatrix& A, int lanczos_steps) {
    D_.build(A, nodes_);
    lambda_ = estimate_lambda_max(A, D_, eigvec_, lanczos_steps, opt_.seed);
    if (!(lambda_ > 0) || !std::isfinite(lambda_))
      throw Error("amg.smoother=" + opt_.kind + ": no positive spectral radius estimate on a level of " +
                  std::to_string(A.rows()) + " rows (matrix not positive definite?)");
  }
  // r = D⁻¹(b − A x)
  void scaled_residual(const SparseMatrix& A, const Vector& b, const Vector& x, Vector& r) {
    const int n = static_cast<int>(A.rows());
    const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
    const double* av = A.valuePtr();
    res_.resize(n);
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (int i = 0; i < n; ++i) {
      double s = b[i];
      for (int k = ao[i]; k < ao[i + 1]; ++k) s -= av[k] * x[ac[k]];
      res_[i] = s;
    }
    D_.apply_inverse(res_, r);
  }

  SmootherOptions opt_;
  NodeLayout nodes_;
  bool chebyshev_;
  BlockDiagonal D_;
  Vector eigvec_, res_, r_, d_;
  double lambda_ = 0;
};
}  // namespace

std::unique_ptr<Smoother> make_block_diagonal_smoother(const SmootherOptions& opt, const SparseMatrix& A,
                                                       const NodeLayout& nodes) {
  return std::make_unique<BlockDiagonalSmoother>(opt, A, nodes);
}

}  // namespace xb::amg
