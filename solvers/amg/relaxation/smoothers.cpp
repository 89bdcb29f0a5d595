#include "smoothers.hpp"

#include "lanczos.hpp"

#include "../../../core/error.hpp"
#include "../../kernels.hpp"
#include "block_chebyshev.hpp"
#include "block_gs.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

namespace xb::amg {

Vector inverse_diagonal(const SparseMatrix& A) {
  Vector d = diagonal(A);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < d.size(); ++i) d[i] = d[i] > 0 ? 1.0 / d[i] : 0.0;
  return d;
}

void multicolor_gs_sweep(const SparseMatrix& A, const Vector& inv_diag, const Coloring& coloring, const Vector& b,
                         Vector& x, bool forward) {
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const int* order = coloring.order.data();
  for (int cc = 0; cc < coloring.num_colors; ++cc) {
    const int c = forward ? cc : coloring.num_colors - 1 - cc;
    const int lo = coloring.color_start[c], hi = coloring.color_start[c + 1];
    // Within one colour the rows are independent, so backward order inside it is irrelevant.
#pragma omp parallel for schedule(static) if (hi - lo > kMinParallelRows)
    for (int t = lo; t < hi; ++t) {
      const int i = order[t];
      double s = b[i];
      for (int k = outer[i]; k < outer[i + 1]; ++k) s -= val[k] * x[cols[k]];
      x[i] += inv_diag[i] * s;
    }
  }
}

double estimate_lambda_max(const SparseMatrix& A, const Vector& inv_diag, Vector& v, int iterations, unsigned seed) {
  // Lanczos on D⁻¹A in the D inner product (D⁻¹A is self-adjoint there). Power iteration
  // approaches λ_max from below too slowly on tet ARAP systems: an estimate 15% low makes the
  // degree-3 Chebyshev polynomial on [λ/30, 1.1λ] amplify the top modes and the V-cycle
  // indefinite (CG then breaks down with r'z <= 0). The largest Ritz value plus its residual
  // |β_k y_k| bounds an eigenvalue from above; it is capped by Gershgorin's bound on D⁻¹A,
  // which is a true upper bound.
  const long n = A.rows();
  if (n == 0) return 0;
  const int* outer = A.outerIndexPtr();
  const double* val = A.valuePtr();
  double gershgorin = 0;
#pragma omp parallel for schedule(static) reduction(max : gershgorin) if (n > kMinParallelRows)
  for (long i = 0; i < n; ++i) {
    double row = 0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) row += std::abs(val[k]);
    gershgorin = std::max(gershgorin, inv_diag[i] * row);
  }
  auto dnorm = [&](const Vector& x) {
    double s = 0;
#pragma omp parallel for schedule(static) reduction(+ : s) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) s += inv_diag[i] > 0 ? x[i] * x[i] / inv_diag[i] : 0.0;
    return std::sqrt(s);
  };
  auto step = [&](const Vector& Aq, const Vector& q, const Vector& q_prev, double a, double beta, Vector& w) {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (long i = 0; i < n; ++i) w[i] = inv_diag[i] * Aq[i] - a * q[i] - beta * q_prev[i];
  };
  const double bound = lanczos_lambda_max(A, v, iterations, seed, dnorm, step);
  return std::isnan(bound) ? gershgorin : std::min(bound, gershgorin);
}

void Smoother::set_lambda_max(double) {
  throw Error("amg.jacobi_omega=level0: smoother '" + name() + "' has no lambda_max(D^-1 A) to share (use jacobi or chebyshev)");
}

void PolynomialSmoother::check_lambda(const SparseMatrix& A) const {
  if (!(relax_.lambda > 0) || !std::isfinite(relax_.lambda))
    throw Error("amg.smoother=" + opt_.kind + ": no positive spectral radius estimate on a level of " +
                std::to_string(A.rows()) + " rows (matrix not positive definite?)");
}

namespace {

// jacobi and chebyshev in D⁻¹A, D the scalar diagonal.
class DiagonalSmoother final : public PolynomialSmoother {
 public:
  DiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A) : PolynomialSmoother(opt, opt.kind == "chebyshev") {
    update(A, opt_.power_iterations);
  }
  void refresh(const SparseMatrix& A) override { update(A, opt_.refresh_power_iterations); }
  void set_lambda_max(double lambda) override { relax_.lambda = lambda; }

 private:
  void update(const SparseMatrix& A, int lanczos_steps) {
    relax_.inv_diag = inverse_diagonal(A);
    relax_.lambda = estimate_lambda_max(A, relax_.inv_diag, eigvec_, lanczos_steps, opt_.seed);
    check_lambda(A);
  }
};

class GaussSeidelSmoother final : public Smoother {
 public:
  GaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A)
      : opt_(opt), coloring_(greedy_coloring(A)), inv_diag_(inverse_diagonal(A)) {}
  std::string name() const override { return "gs"; }
  bool symmetric_from_zero() const override { return false; }
  void refresh(const SparseMatrix& A) override { inv_diag_ = inverse_diagonal(A); }  // colouring: pattern only
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    if (x_zero) x.setZero();
    for (int s = 0; s < opt_.sweeps; ++s) multicolor_gs_sweep(A, inv_diag_, coloring_, b, x, true);
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override {
    for (int s = 0; s < opt_.sweeps; ++s) multicolor_gs_sweep(A, inv_diag_, coloring_, b, x, false);
  }

 private:
  SmootherOptions opt_;
  Coloring coloring_;
  Vector inv_diag_;
};

}  // namespace

const char* const kSmootherKinds = "jacobi, chebyshev, gs, block_gs, block_jacobi, block_chebyshev";

std::unique_ptr<Smoother> make_smoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes,
                                        const BlockOperator* blocks) {
  if (opt.sweeps < 1) throw Error("amg.smoother_sweeps must be >= 1");
  if (opt.degree < 1) throw Error("amg.chebyshev_degree must be >= 1");
  if (opt.kind == "jacobi" || opt.kind == "chebyshev") return std::make_unique<DiagonalSmoother>(opt, A);
  if (opt.kind == "gs") return std::make_unique<GaussSeidelSmoother>(opt, A);
  if (opt.kind == "block_gs") return std::make_unique<BlockGaussSeidelSmoother>(opt, A, nodes);
  if (opt.kind == "block_jacobi" || opt.kind == "block_chebyshev") return make_block_diagonal_smoother(opt, A, nodes, blocks);
  throw Error("amg.smoother: unknown smoother '" + opt.kind + "' (valid: " + kSmootherKinds + ")");
}

}  // namespace xb::amg
