// The chebyshev smoother (chebyshev.hpp): the fused smoother equals the textbook three-term
// recurrence (Saad, Alg. 12.1) on a dense copy, and at every degree its error propagation is the
// scaled Chebyshev polynomial of D⁻¹A.
#include "core/error.hpp"
#include "solvers/amg/relaxation/smoothers.hpp"

#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(Chebyshev, ChebyshevSmootherIsTheThreeTermRecurrence) {
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
TEST(Chebyshev, ChebyshevOfDegreeDIsTheScaledChebyshevPolynomial) {
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
