#include "smoothers.hpp"

#include "../../problems/error.hpp"
#include "../kernels.hpp"

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
  const long n = A.rows();
  if (n == 0) return 0;
  if (v.size() != n || v.squaredNorm() == 0) {
    std::mt19937_64 rng(seed * 7919ull + 17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    v.resize(n);
    for (long i = 0; i < n; ++i) v[i] = u(rng);
  }
  Vector Av(n);
  double lambda = 0;
  // Power iteration on D⁻¹A (self-adjoint in the D inner product): RQ = vᵀAv / vᵀDv ≤ λ_max.
  for (int it = 0; it < std::max(1, iterations); ++it) {
    spmv(A, v, Av);
    double vAv = 0, vDv = 0;
#pragma omp parallel for schedule(static) reduction(+ : vAv, vDv)
    for (long i = 0; i < n; ++i) {
      vAv += v[i] * Av[i];
      vDv += inv_diag[i] > 0 ? v[i] * v[i] / inv_diag[i] : 0.0;
    }
    if (!(vDv > 0)) break;
    lambda = std::max(lambda, vAv / vDv);
    // v ← D⁻¹Av, scaled to unit D-norm.
    double nrm = 0;
#pragma omp parallel for schedule(static) reduction(+ : nrm)
    for (long i = 0; i < n; ++i) {
      v[i] = inv_diag[i] * Av[i];
      nrm += inv_diag[i] > 0 ? v[i] * v[i] / inv_diag[i] : 0.0;
    }
    if (!(nrm > 0) || !std::isfinite(nrm)) break;
    v /= std::sqrt(nrm);
  }
  return lambda;
}

namespace {

class DiagonalSmoother : public Smoother {
 public:
  DiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A) : opt_(opt) {
    inv_diag_ = inverse_diagonal(A);
    lambda_ = estimate_lambda_max(A, inv_diag_, eigvec_, opt_.power_iterations, opt_.seed);
    check(A);
  }
  void refresh(const SparseMatrix& A) override {
    inv_diag_ = inverse_diagonal(A);
    lambda_ = estimate_lambda_max(A, inv_diag_, eigvec_, opt_.refresh_power_iterations, opt_.seed);
    check(A);
  }
  double lambda_max() const override { return lambda_; }

 protected:
  void check(const SparseMatrix& A) {
    if (!(lambda_ > 0) || !std::isfinite(lambda_))
      throw Error("amg.smoother=" + opt_.kind + ": no positive spectral radius estimate on a level of " +
                  std::to_string(A.rows()) + " rows (matrix not positive definite?)");
  }
  // r = D⁻¹(b − A x)
  void scaled_residual(const SparseMatrix& A, const Vector& b, const Vector& x, Vector& r) const {
    const int n = static_cast<int>(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* cols = A.innerIndexPtr();
    const double* val = A.valuePtr();
    r.resize(n);
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (int i = 0; i < n; ++i) {
      double s = b[i];
      for (int k = outer[i]; k < outer[i + 1]; ++k) s -= val[k] * x[cols[k]];
      r[i] = inv_diag_[i] * s;
    }
  }
  SmootherOptions opt_;
  Vector inv_diag_, eigvec_, r_, d_;
  double lambda_ = 0;
};

class JacobiSmoother final : public DiagonalSmoother {
 public:
  using DiagonalSmoother::DiagonalSmoother;
  std::string name() const override { return "jacobi"; }
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    const double omega = 1.0 / lambda_;
    const long n = b.size();
    for (int s = 0; s < opt_.sweeps; ++s) {
      if (s == 0 && x_zero) {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
        for (long i = 0; i < n; ++i) x[i] = omega * inv_diag_[i] * b[i];
        continue;
      }
      scaled_residual(A, b, x, r_);
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
      for (long i = 0; i < n; ++i) x[i] += omega * r_[i];
    }
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override { presmooth(A, b, x, false); }
};

class ChebyshevSmoother final : public DiagonalSmoother {
 public:
  using DiagonalSmoother::DiagonalSmoother;
  std::string name() const override { return "chebyshev"; }
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    for (int s = 0; s < opt_.sweeps; ++s) apply(A, b, x, x_zero && s == 0);
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override { presmooth(A, b, x, false); }

 private:
  static constexpr int kDegree = 3;
  // Chebyshev iteration for D⁻¹A with eigenvalues in [a, b] (Saad, Alg. 12.1): the error is
  // multiplied by a fixed polynomial of D⁻¹A, the same before and after, hence symmetric.
  void apply(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) {
    const double hi = 1.1 * lambda_, lo = lambda_ / 30.0;
    const double theta = 0.5 * (hi + lo), delta = 0.5 * (hi - lo), sigma = theta / delta;
    double rho = 1.0 / sigma;
    const long n = b.size();
    if (x_zero) {
      r_.resize(n);
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
      for (long i = 0; i < n; ++i) r_[i] = inv_diag_[i] * b[i];
    } else {
      scaled_residual(A, b, x, r_);
    }
    d_ = r_ / theta;
    for (int k = 1;; ++k) {
      if (x_zero && k == 1) {
        x = d_;
      } else {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
        for (long i = 0; i < n; ++i) x[i] += d_[i];
      }
      if (k == kDegree) break;
      scaled_residual(A, b, x, r_);
      const double rho_new = 1.0 / (2.0 * sigma - rho);
      const double c1 = rho_new * rho, c2 = 2.0 * rho_new / delta;
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
      for (long i = 0; i < n; ++i) d_[i] = c1 * d_[i] + c2 * r_[i];
      rho = rho_new;
    }
  }
};

class GaussSeidelSmoother final : public Smoother {
 public:
  GaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A)
      : opt_(opt), coloring_(greedy_coloring(A)), inv_diag_(inverse_diagonal(A)) {}
  std::string name() const override { return "gs"; }
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

std::unique_ptr<Smoother> make_smoother(const SmootherOptions& opt, const SparseMatrix& A) {
  if (opt.sweeps < 1) throw Error("amg.smoother_sweeps must be >= 1");
  if (opt.kind == "jacobi") return std::make_unique<JacobiSmoother>(opt, A);
  if (opt.kind == "chebyshev") return std::make_unique<ChebyshevSmoother>(opt, A);
  if (opt.kind == "gs") return std::make_unique<GaussSeidelSmoother>(opt, A);
  throw Error("amg.smoother: unknown smoother '" + opt.kind + "' (valid: jacobi, chebyshev, gs)");
}

}  // namespace xb::amg
