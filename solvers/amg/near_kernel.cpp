#include "near_kernel.hpp"

#include "../../core/error.hpp"
#include "../kernels.hpp"
#include "relaxation/gauss_seidel.hpp"

#include <cmath>
#include <random>

namespace xb::amg {

Eigen::MatrixXd near_kernel_candidates(const SparseMatrix& A, const NearKernelOptions& opt, const Coloring* coloring,
                                       int block_size, const Eigen::MatrixXd* given) {
  const long n = A.rows();
  if (opt.kind == "ones" && block_size <= 1) return Eigen::MatrixXd::Ones(n, 1);
  if (opt.kind == "ones") {
    if (n % block_size != 0) throw Error("amg.near_kernel=ones: block size does not divide the rows");
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n, block_size);
    for (long i = 0; i < n; ++i) B(i, i % block_size) = 1.0;
    return B;
  }
  if (opt.kind == "rigid") {
    if (!given || given->rows() != n || given->cols() < 1)
      throw Error("amg.near_kernel=rigid: the near-kernel basis has " + std::to_string(given ? given->rows() : 0) +
                  " rows, the matrix " + std::to_string(n));
    if (opt.extra < 0) throw Error("amg.near_kernel: the number of extra candidates must be >= 0");
    if (opt.extra == 0) return *given;
    // Adaptive-SA-style enrichment: relaxed random vectors carry the low-energy modes the rigid
    // modes miss (nearly volume-preserving motions of stretched tets).
    Eigen::MatrixXd B(n, given->cols() + opt.extra);
    B << *given, relaxed_random_vectors(A, opt.extra, opt.sweeps, opt.seed, coloring);
    return B;
  }
  if (opt.kind == "gs_authors") return gs_authors_vectors(A, opt.seed);
  if (opt.kind != "gs") throw Error("amg.near_kernel: unknown kind '" + opt.kind + "' (valid: auto, ones, gs, gs_authors, rigid)");
  if (opt.vectors < 1) throw Error("amg.near_kernel_vectors must be >= 1");
  return relaxed_random_vectors(A, opt.vectors, opt.sweeps, opt.seed, coloring);
}

Eigen::MatrixXd relaxed_random_vectors(const SparseMatrix& A, int count, int sweeps, unsigned seed,
                                       const Coloring* coloring) {
  const long n = A.rows();
  Coloring own;
  if (!coloring) {
    own = greedy_coloring(A);
    coloring = &own;
  }
  const Vector inv_diag = inverse_diagonal(A);
  Eigen::MatrixXd B(n, count);
  const Vector zero = Vector::Zero(n);
  for (int v = 0; v < count; ++v) {
    // The random start is drawn sequentially from one stream per vector: the same for every
    // thread count.
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 1000003ull + static_cast<std::uint64_t>(v));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vector x(n);
    for (long i = 0; i < n; ++i) x[i] = u(rng);
    for (int s = 0; s < sweeps; ++s) {
      multicolor_gs_sweep(A, inv_diag, *coloring, zero, x, true);
      // Keep the scale away from underflow: GS on A x = 0 shrinks x every sweep.
      const double nx = norm2(x);
      if (nx > 0) x /= nx;
    }
    const double nx = norm2(x);
    if (!(nx > 0) || !std::isfinite(nx)) throw Error("amg.near_kernel: a relaxed candidate vanished or is not finite");
    B.col(v) = x / nx;
  }
  return B;
}

Eigen::MatrixXd gs_authors_vectors(const SparseMatrix& A, unsigned seed) {
  const long n = A.rows();
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const Vector inv_diag = inverse_diagonal(A);
  const double max_abs = A.nonZeros() > 0 ? Eigen::Map<const Vector>(val, A.nonZeros()).cwiseAbs().maxCoeff() : 1.0;
  Eigen::MatrixXd B(n, kGsAuthorsVectors);
  for (int v = 0; v < kGsAuthorsVectors; ++v) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 1000003ull + static_cast<std::uint64_t>(v));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Vector x(n);
    for (long i = 0; i < n; ++i) x[i] = u(rng) * max_abs;
    for (int s = 0; s < kGsAuthorsSweeps; ++s) {
      for (long i = 0; i < n; ++i) {  // sequential: row i sees rows < i of this sweep
        double r = 0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) r -= val[k] * x[cols[k]];
        x[i] += inv_diag[i] * r;
      }
      const double nx = norm2(x);  // the direction is what counts: keep the scale from underflow
      if (nx > 0) x /= nx;
    }
    const double nx = norm2(x);
    if (!(nx > 0) || !std::isfinite(nx)) throw Error("amg.near_kernel=gs_authors: a relaxed candidate vanished or is not finite");
    B.col(v) = x / nx;
  }
  return B;
}

}  // namespace xb::amg
