// Moré–Sorensen with CHOLMOD (solvers/direct/more_sorensen.hpp) against a dense eigendecomposition:
// the shift σ of the secular equation ‖(K + σD)⁻¹g‖_D = Δ, the interior Newton step, and the hard
// case closed along the lowest eigenvector.
#include "solvers/direct/more_sorensen.hpp"
#include "solvers/solver_settings.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>

using namespace xb;

namespace {
// A sparse indefinite K (a 1D Laplacian-like band shifted down) and a positive diagonal D.
struct Case {
  Eigen::MatrixXd K;
  Vector D, g;
};
Case make_case(int n, double shift) {
  Case c;
  c.K = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    c.K(i, i) = 2.0 + 0.1 * i - shift;
    if (i + 1 < n) c.K(i, i + 1) = c.K(i + 1, i) = -1.0;
  }
  c.D = Vector::LinSpaced(n, 1, 3);
  c.g = Vector::LinSpaced(n, 1, -1) + 0.3 * Vector::Ones(n);
  return c;
}

// The dense answer: Ĥ = D^-½KD^-½ = QΛQᵀ, ĝ = D^-½g, ‖p(σ)‖²_D = Σ (qᵢᵀĝ)²/(λᵢ + σ)², σ* by bisection.
double dense_sigma(const Case& c, double radius, double& lambda_min) {
  const Vector s = c.D.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd H = s.asDiagonal() * c.K * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  const Vector a = es.eigenvectors().transpose() * (s.cwiseProduct(c.g));
  lambda_min = es.eigenvalues()[0];
  auto norm = [&](double sigma) { return std::sqrt((a.array() / (es.eigenvalues().array() + sigma)).square().sum()); };
  double lo = std::max(0.0, -lambda_min), hi = lo + 1;
  while (norm(hi) > radius) hi *= 2;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (norm(mid) > radius ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

MoreSorensen make(double accuracy) {
  SolverSettings s;
  s.cholmod.refactor = "always";
  return MoreSorensen(make_linear_solver("cholmod", s), accuracy, 60);
}
double model(const Case& c, const Vector& p) { return c.g.dot(p) + 0.5 * p.dot(c.K * p); }
}  // namespace

TEST(MoreSorensen, ShiftSolvesTheSecularEquation) {
  const Case c = make_case(40, 1.5);
  double lambda_min;
  const double radius = 0.8;
  const double sigma = dense_sigma(c, radius, lambda_min);
  ASSERT_LT(lambda_min, 0);  // K is indefinite
  MoreSorensen ms = make(1e-10);
  const MoreSorensenResult r = ms.solve(SparseMatrix(c.K.sparseView()), c.D, c.g, radius);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_NEAR(r.sigma, sigma, 1e-7 * sigma);
  EXPECT_TRUE(r.boundary);
  EXPECT_NEAR(r.norm, radius, 1e-9);
  const Vector p = -(c.K + sigma * Eigen::MatrixXd(c.D.asDiagonal())).ldlt().solve(c.g);
  EXPECT_LT((r.p - p).norm(), 1e-6 * p.norm());
  EXPECT_NEAR(r.model, model(c, r.p), 1e-10 * std::abs(r.model));
}

// The default accuracy (κ = 0.1): a few factorisations, ‖p‖_D within 10% of Δ, the model within
// κ(2 − κ) of the optimum (Moré–Sorensen's guarantee).
TEST(MoreSorensen, LooseAccuracyIsCheapAndNearOptimal) {
  const Case c = make_case(40, 1.5);
  double lambda_min;
  const double radius = 0.8;
  const double sigma = dense_sigma(c, radius, lambda_min);
  const Vector best = -(c.K + sigma * Eigen::MatrixXd(c.D.asDiagonal())).ldlt().solve(c.g);
  MoreSorensen ms = make(0.1);
  const MoreSorensenResult r = ms.solve(SparseMatrix(c.K.sparseView()), c.D, c.g, radius);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_LE(r.factorisations, 12);
  EXPECT_LE(std::abs(r.norm - radius), 0.1 * radius);
  EXPECT_LE(model(c, r.p), (1 - 0.1 * 1.9) * model(c, best));
}

TEST(MoreSorensen, PositiveDefiniteInteriorIsTheNewtonStep) {
  const Case c = make_case(30, 0);
  const Vector newton = -c.K.ldlt().solve(c.g);
  MoreSorensen ms = make(0.1);
  const MoreSorensenResult r = ms.solve(SparseMatrix(c.K.sparseView()), c.D, c.g, 10 * newton.norm() * 2);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.sigma, 0);
  EXPECT_FALSE(r.boundary);
  EXPECT_EQ(r.factorisations, 1);
  EXPECT_LT((r.p - newton).norm(), 1e-10 * newton.norm());
}

// g ⟂ the lowest eigenvector (in D's metric): ‖p(σ)‖_D < Δ for every admissible σ, the hard case.
// With that eigenvector as u the step is p(−λ_min) + τu on the boundary, the model's minimum.
TEST(MoreSorensen, HardCaseClosesAlongTheGivenDirection) {
  const int n = 20;
  Case c;
  c.D = Vector::Ones(n);
  Vector ev = Vector::LinSpaced(n, -1, 6);
  c.K = Eigen::MatrixXd(ev.asDiagonal());
  c.K(1, 2) = c.K(2, 1) = 0.2;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(c.K);
  const Vector q = es.eigenvectors().col(0);
  c.g = Vector::LinSpaced(n, 0.5, 1);
  c.g -= q.dot(c.g) * q;  // no component along the lowest eigenvector
  const double lmin = es.eigenvalues()[0];
  const double radius = 5;
  // The dense optimum: σ = −λ_min, p = −(K − λ_min I)⁺g + τq with ‖p‖ = Δ.
  Eigen::MatrixXd S = c.K - lmin * Eigen::MatrixXd::Identity(n, n);
  const Vector p0 = -S.completeOrthogonalDecomposition().solve(c.g);
  ASSERT_LT(p0.norm(), radius);
  const double tau = std::sqrt(radius * radius - p0.squaredNorm());
  const double best = model(c, p0 + tau * q);
  MoreSorensen ms = make(0.1);
  const MoreSorensenResult r = ms.solve(SparseMatrix(c.K.sparseView()), c.D, c.g, radius, &q);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(r.hard_case);
  EXPECT_NEAR(r.p.norm(), radius, 1e-9 * radius);
  EXPECT_LE(model(c, r.p), (1 - 0.1 * 1.9) * best);
}
