// Steihaug–Toint CG (solvers/krylov/steihaug.hpp) against dense computations: the interior step is
// the Newton step, negative curvature goes to the boundary (where PCG reports a breakdown), the
// region is measured in the preconditioner's norm, and the step never does worse than the Cauchy
// point.
#include "solvers/krylov/pcg.hpp"
#include "solvers/krylov/steihaug.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>

using namespace xb;

namespace {
// Q diag(eigenvalues) Qᵀ with a fixed orthogonal Q, as a sparse (dense-pattern) matrix.
Eigen::MatrixXd rotated(const Eigen::VectorXd& eigenvalues, unsigned seed) {
  std::srand(seed);
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(eigenvalues.size(), eigenvalues.size());
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd Q = qr.householderQ();
  return Q * eigenvalues.asDiagonal() * Q.transpose();
}
SparseMatrix sparse(const Eigen::MatrixXd& A) { return A.sparseView(0, 0); }
double model(const Eigen::MatrixXd& K, const Vector& g, const Vector& p) { return g.dot(p) + 0.5 * p.dot(K * p); }
}  // namespace

TEST(Steihaug, InteriorIsTheNewtonStep) {
  Eigen::VectorXd ev(6);
  ev << 1, 2, 3, 5, 8, 13;
  const Eigen::MatrixXd K = rotated(ev, 3);
  const Vector g = Vector::LinSpaced(6, -1, 1.5);
  const Vector newton = -K.ldlt().solve(g);
  const SteihaugResult r = steihaug_toint(sparse(K), g, 10 * newton.norm(), nullptr, 1e-12, 100);
  EXPECT_EQ(r.exit, SteihaugExit::interior);
  EXPECT_LT((r.p - newton).norm(), 1e-9 * newton.norm());
  EXPECT_NEAR(r.model, model(K, g, newton), 1e-10 * std::abs(model(K, g, newton)));
  EXPECT_NEAR(r.norm, newton.norm(), 1e-9 * newton.norm());
}

// The first direction −g has negative curvature: the step is −Δg/‖g‖ exactly, where PCG breaks down.
TEST(Steihaug, NegativeCurvatureGoesToTheBoundary) {
  Eigen::VectorXd ev(5);
  ev << -4, 1, 2, 3, 4;
  const Eigen::MatrixXd K = rotated(ev, 7);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
  const Vector g = es.eigenvectors().col(0) + 0.1 * es.eigenvectors().col(1);  // gᵀKg < 0
  ASSERT_LT(g.dot(K * g), 0);
  const double radius = 0.7;
  const SteihaugResult r = steihaug_toint(sparse(K), g, radius, nullptr, 1e-10, 100);
  EXPECT_EQ(r.exit, SteihaugExit::negative_curvature);
  EXPECT_EQ(r.iterations, 1);
  const Vector expected = -radius * g / g.norm();
  EXPECT_LT((r.p - expected).norm(), 1e-12);
  EXPECT_NEAR(r.curvature, g.dot(K * g) / g.squaredNorm(), 1e-12);
  EXPECT_NEAR(r.model, model(K, g, expected), 1e-12);
  Vector x;
  const LinearStats st = pcg(sparse(K), -g, x, nullptr, 1e-10, 100);
  EXPECT_EQ(st.status, LinearStatus::breakdown);  // what Steihaug–Toint turns into a step
}

// Negative curvature met at the second CG direction: the step lies in span{g, Kg}, on the boundary,
// and lowers the model below the Cauchy point (the model's minimiser along −g inside the region).
TEST(Steihaug, LaterNegativeCurvatureStaysInTheKrylovSpace) {
  Eigen::VectorXd ev(6);
  ev << -2, 1, 3, 6, 9, 12;
  const Eigen::MatrixXd K = rotated(ev, 11);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
  Vector g = 1.5 * es.eigenvectors().col(0);
  for (int i = 1; i < 6; ++i) g += es.eigenvectors().col(i);
  ASSERT_GT(g.dot(K * g), 0);  // −g itself has positive curvature, but K on span{g, Kg} has not
  const Vector Kg = K * g;
  ASSERT_LT(g.dot(Kg) * Kg.dot(K * Kg) - Kg.squaredNorm() * Kg.squaredNorm(), 0);
  const double radius = 50;
  const SteihaugResult r = steihaug_toint(sparse(K), g, radius, nullptr, 1e-12, 100);
  EXPECT_EQ(r.exit, SteihaugExit::negative_curvature);
  EXPECT_EQ(r.iterations, 2);
  EXPECT_NEAR(r.p.norm(), radius, 1e-9 * radius);
  EXPECT_NEAR(r.norm, radius, 1e-9 * radius);
  Eigen::MatrixXd basis(6, 2);
  basis << g, K * g;
  const Vector in_span = basis * basis.colPivHouseholderQr().solve(r.p);
  EXPECT_LT((r.p - in_span).norm(), 1e-9 * radius);
  const double gKg = g.dot(K * g);
  const double t = std::min(g.squaredNorm() / gKg, radius / g.norm());
  EXPECT_LT(r.model, model(K, g, -t * g));
  EXPECT_NEAR(r.model, model(K, g, r.p), 1e-9 * std::abs(r.model));
}

// With P = diag(d) the region is ‖p‖_P = √(pᵀPp) ≤ Δ: the recurrences' norm is the true one.
TEST(Steihaug, PreconditionedRegionIsInThePreconditionersNorm) {
  Eigen::VectorXd ev(8);
  ev << 0.5, 1, 2, 4, 8, 16, 32, 64;
  const Eigen::MatrixXd K = rotated(ev, 5);
  const Vector d = Vector::LinSpaced(8, 1, 30);
  const Vector g = Vector::LinSpaced(8, 1, -2);
  const Preconditioner P = [&](const Vector& r, Vector& z) { z = r.cwiseQuotient(d); };
  const double newton_norm = std::sqrt((K.ldlt().solve(g)).cwiseAbs2().dot(d));
  const double radius = 0.3 * newton_norm;
  const SteihaugResult r = steihaug_toint(sparse(K), g, radius, P, 1e-12, 100);
  EXPECT_EQ(r.exit, SteihaugExit::boundary);
  EXPECT_NEAR(std::sqrt(r.p.cwiseAbs2().dot(d)), radius, 1e-9 * radius);
  EXPECT_NEAR(r.norm, radius, 1e-9 * radius);
}

TEST(Steihaug, BoundaryStepSolvesTheQuadratic) {
  // ‖p + τd‖ = Δ from inside, both signs of pᵀd (the two forms of the root).
  for (double pd : {-0.3, 0.4}) {
    const double pp = 0.25, dd = 2, radius = 1.5;
    const double tau = step_to_boundary(pp, pd, dd, radius);
    EXPECT_GT(tau, 0);
    EXPECT_NEAR(pp + 2 * tau * pd + tau * tau * dd, radius * radius, 1e-12);
  }
}
