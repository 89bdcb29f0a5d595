// The parallel kernels against plain Eigen: row blocks cover the rows once, in order, with
// balanced non-zeros; the fused SpMV + dot and PCG update equal their unfused forms; the fused
// Chebyshev smoother equals the textbook three-term recurrence (Saad, Alg. 12.1) on a dense copy,
// and at every degree its error propagation is the scaled Chebyshev polynomial of D⁻¹A.
#include "solvers/amg/relaxation/smoothers.hpp"
#include "solvers/kernels.hpp"

#include "solvers/amg/amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;

TEST(Kernels, RowBlocksCoverTheRowsWithBalancedNonZeros) {
  const SparseMatrix A = xb::test::poisson2d(37);
  const int n = static_cast<int>(A.rows());
  for (int T : {1, 2, 3, 7}) {
    int next = 0;
    for (int t = 0; t < T; ++t) {
      int lo, hi;
      row_block(A.outerIndexPtr(), n, t, T, lo, hi);
      EXPECT_EQ(lo, next);
      EXPECT_LE(lo, hi);
      const long nnz = A.outerIndexPtr()[hi] - A.outerIndexPtr()[lo];
      EXPECT_LE(std::abs(nnz - A.nonZeros() / T), 10) << T;  // ≤ 2 rows of 5 off the share
      next = hi;
    }
    EXPECT_EQ(next, n);
  }
}

TEST(Kernels, FusedKernelsEqualTheirUnfusedForms) {
  const SparseMatrix A = xb::test::poisson3d(9);
  const Vector x = xb::test::random_vector(A.rows(), 1), b = xb::test::random_vector(A.rows(), 2);
  Vector y, r;
  const double xy = spmv_dot(A, x, y);
  const Vector ref = A * x;
  EXPECT_LE((y - ref).norm(), 1e-14 * ref.norm());
  EXPECT_NEAR(xy, x.dot(ref), 1e-12 * std::abs(x.dot(ref)));
  residual(A, x, b, r);
  EXPECT_LE((r - (b - ref)).norm(), 1e-14 * b.norm());
  Vector xx = b, rr = r;
  const double rr2 = cg_update(0.3, x, y, xx, rr);
  EXPECT_LE((xx - (b + 0.3 * x)).norm(), 1e-14 * xx.norm());
  EXPECT_LE((rr - (r - 0.3 * ref)).norm(), 1e-14 * rr.norm());
  EXPECT_NEAR(rr2, rr.squaredNorm(), 1e-12 * rr2);
}

TEST(Kernels, ChebyshevSmootherIsTheThreeTermRecurrence) {
  const SparseMatrix A = xb::test::poisson2d(12);
  const Vector b = xb::test::random_vector(A.rows(), 3), x0 = xb::test::random_vector(A.rows(), 4);
  amg::SmootherOptions o;
  o.kind = "chebyshev";
  auto sm = amg::make_smoother(o, A);
  // Saad, Alg. 12.1 on D⁻¹A with [λ/30, 1.1λ], three steps, dense.
  const Eigen::MatrixXd Ad(A);
  const Vector dinv = Ad.diagonal().cwiseInverse();
  const double lam = sm->lambda_max(), hi = 1.1 * lam, lo = lam / 30;
  const double theta = (hi + lo) / 2, delta = (hi - lo) / 2, sigma = theta / delta;
  for (bool zero : {false, true}) {
    Vector x = zero ? Vector::Zero(A.rows()) : x0;
    Vector d = dinv.cwiseProduct(b - Ad * x) / theta;
    double rho = 1 / sigma;
    for (int k = 1; k <= 3; ++k) {
      x += d;
      if (k == 3) break;
      const double rho_new = 1 / (2 * sigma - rho);
      d = rho_new * rho * d + 2 * rho_new / delta * dinv.cwiseProduct(b - Ad * x);
      rho = rho_new;
    }
    Vector xs = zero ? Vector::Zero(A.rows()) : x0;
    sm->presmooth(A, b, xs, zero);
    EXPECT_LE((xs - x).norm(), 1e-12 * x.norm()) << zero;
  }
}

// amg.chebyshev_degree: after d steps from x0 the error is p_d(D⁻¹A) e0 with
// p_d(t) = T_d((θ − t)/δ) / T_d(θ/δ) on [λ/30, 1.1λ] — checked through the eigenvectors of the
// symmetric D^{-1/2} A D^{-1/2}, independent of the recurrence.
TEST(Kernels, ChebyshevOfDegreeDIsTheScaledChebyshevPolynomial) {
  const SparseMatrix A = xb::test::poisson2d(9);
  const Eigen::MatrixXd Ad(A);
  const Vector b = xb::test::random_vector(A.rows(), 5), x0 = xb::test::random_vector(A.rows(), 6);
  const Vector x_star = Ad.llt().solve(b);
  const Vector dh = Ad.diagonal().cwiseSqrt();
  const Eigen::MatrixXd S = dh.cwiseInverse().asDiagonal() * Ad * dh.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  auto cheb_T = [](int d, double y) {
    return std::abs(y) <= 1 ? std::cos(d * std::acos(y)) : std::cosh(d * std::acosh(std::abs(y))) * (y < 0 && d % 2 ? -1 : 1);
  };
  for (int degree : {1, 2, 4, 5}) {
    amg::SmootherOptions o;
    o.kind = "chebyshev";
    o.degree = degree;
    auto sm = amg::make_smoother(o, A);
    const double lam = sm->lambda_max(), hi = 1.1 * lam, lo = lam / 30;
    const double theta = (hi + lo) / 2, delta = (hi - lo) / 2;
    Vector p(A.rows());
    for (int k = 0; k < A.rows(); ++k)
      p[k] = cheb_T(degree, (theta - eig.eigenvalues()[k]) / delta) / cheb_T(degree, theta / delta);
    const Vector e0 = dh.cwiseProduct(x0 - x_star);  // D^{1/2} e0
    const Vector expect = dh.cwiseInverse().cwiseProduct(eig.eigenvectors() * p.cwiseProduct(eig.eigenvectors().transpose() * e0));
    Vector x = x0;
    sm->presmooth(A, b, x, false);
    EXPECT_LE((x - x_star - expect).norm(), 1e-10 * (x0 - x_star).norm()) << degree;
  }
}
