#include "near_kernel.hpp"

#include "../../problems/error.hpp"
#include "../kernels.hpp"
#include "smoothers.hpp"

#include <cmath>
#include <random>

namespace xb::amg {

Eigen::MatrixXd near_kernel_candidates(const SparseMatrix& A, const NearKernelOptions& opt, const Coloring* coloring) {
  const long n = A.rows();
  if (opt.kind == "ones") return Eigen::MatrixXd::Ones(n, 1);
  if (opt.kind != "gs") throw Error("amg.near_kernel: unknown kind '" + opt.kind + "' (valid: ones, gs)");
  if (opt.vectors < 1) throw Error("amg.near_kernel_vectors must be >= 1");
  Coloring own;
  if (!coloring) {
    own = greedy_coloring(A);
    coloring = &own;
  }
  const Vector inv_diag = inverse_diagonal(A);
  Eigen::MatrixXd B(n, opt.vectors);
  const Vector zero = Vector::Zero(n);
  for (int v = 0; v < opt.vectors; ++v) {
    // The random start is drawn sequentially from one stream per vector: the same for every
    // thread count.
    std::mt19937_64 rng(static_cast<std::uint64_t>(opt.seed) * 1000003ull + static_cast<std::uint64_t>(v));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vector x(n);
    for (long i = 0; i < n; ++i) x[i] = u(rng);
    for (int s = 0; s < opt.sweeps; ++s) {
      multicolor_gs_sweep(A, inv_diag, *coloring, zero, x, true);
      // Keep the scale away from underflow: GS on A x = 0 shrinks x every sweep.
      const double nx = norm2(x);
      if (nx > 0) x /= nx;
    }
    const double nx = norm2(x);
    if (!(nx > 0) || !std::isfinite(nx)) throw Error("amg.near_kernel=gs: the smoothed candidate vanished or is not finite");
    B.col(v) = x / nx;
  }
  return B;
}

}  // namespace xb::amg
