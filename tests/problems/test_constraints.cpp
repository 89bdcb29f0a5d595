// Constraint gradients against central finite differences on random non-degenerate configurations.
#include "problems/constraints.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {
std::mt19937 rng(42);
Eigen::Vector3d rand3(double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return {u(rng), u(rng), u(rng)};
}
}  // namespace

TEST(Distance, GradientMatchesFiniteDifferences) {
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Vector3d p = rand3(), q = rand3();
    const double rest = 0.5;
    Eigen::Vector3d gp, gq;
    distance_constraint(p, q, rest, &gp, &gq);
    const double h = 1e-6;
    for (int d = 0; d < 3; ++d) {
      Eigen::Vector3d e = Eigen::Vector3d::Unit(d) * h;
      const double fp = (distance_constraint(p + e, q, rest, nullptr, nullptr) - distance_constraint(p - e, q, rest, nullptr, nullptr)) / (2 * h);
      const double fq = (distance_constraint(p, q + e, rest, nullptr, nullptr) - distance_constraint(p, q - e, rest, nullptr, nullptr)) / (2 * h);
      EXPECT_NEAR(fp, gp[d], 1e-6 * std::max(1.0, std::abs(gp[d])));
      EXPECT_NEAR(fq, gq[d], 1e-6 * std::max(1.0, std::abs(gq[d])));
    }
  }
}

TEST(Distance, ValueAndCoincidentPoints) {
  Eigen::Vector3d gp, gq;
  EXPECT_DOUBLE_EQ(distance_constraint({0, 0, 0}, {3, 4, 0}, 2.0, &gp, &gq), 3.0);
  EXPECT_NEAR(gp[0], -0.6, 1e-15);
  EXPECT_DOUBLE_EQ(distance_constraint({1, 1, 1}, {1, 1, 1}, 2.0, &gp, &gq), -2.0);
  EXPECT_EQ(gp.norm(), 0.0);  // undefined direction: no force
}

// The rotation-variant SVD reproduces F with proper rotations.
TEST(TetArap, RotationVariantSvd) {
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Random();
    Eigen::Matrix3d U, V;
    Eigen::Vector3d s;
    svd_rv(F, U, s, V);
    EXPECT_NEAR((U * s.asDiagonal() * V.transpose() - F).norm(), 0, 1e-12);
    EXPECT_NEAR(U.determinant(), 1, 1e-12);
    EXPECT_NEAR(V.determinant(), 1, 1e-12);
  }
}

TEST(TetArap, GradientMatchesFiniteDifferences) {
  int checked = 0;
  for (int trial = 0; trial < 100; ++trial) {
    // A rest tet and a random deformation of it, including inverted ones.
    std::array<Eigen::Vector3d, 4> X = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 0, 1)};
    for (auto& v : X) v += rand3(0.2);
    Eigen::Matrix3d Dm;
    for (int c = 0; c < 3; ++c) Dm.col(c) = X[c + 1] - X[0];
    if (std::abs(Dm.determinant()) < 0.1) continue;
    const Eigen::Matrix3d Dm_inv = Dm.inverse();
    std::array<Eigen::Vector3d, 4> x;
    for (int k = 0; k < 4; ++k) x[k] = X[k] + rand3(0.4);
    // Stay away from the kinks: C ≈ 0 and repeated/zero singular values.
    Eigen::Matrix3d Ds;
    for (int c = 0; c < 3; ++c) Ds.col(c) = x[c + 1] - x[0];
    Eigen::Matrix3d U, V;
    Eigen::Vector3d s;
    svd_rv(Ds * Dm_inv, U, s, V);
    if (std::abs(s[2]) < 0.05 || s[0] - s[1] < 0.05 || s[1] - std::abs(s[2]) < 0.05) continue;
    std::array<Eigen::Vector3d, 4> g;
    const double C = tet_arap_constraint(x[0], x[1], x[2], x[3], Dm_inv, &g);
    if (C < 0.05) continue;
    EXPECT_NEAR(C, std::sqrt((s.array() - 1).square().sum()), 1e-12);
    const double h = 1e-6;
    for (int k = 0; k < 4; ++k)
      for (int d = 0; d < 3; ++d) {
        auto xp = x, xm = x;
        xp[k][d] += h;
        xm[k][d] -= h;
        const double fd = (tet_arap_constraint(xp[0], xp[1], xp[2], xp[3], Dm_inv, nullptr) -
                           tet_arap_constraint(xm[0], xm[1], xm[2], xm[3], Dm_inv, nullptr)) /
                          (2 * h);
        EXPECT_NEAR(fd, g[k][d], 1e-6 * std::max(1.0, g[k].norm())) << "trial " << trial << " vertex " << k;
      }
    ++checked;
  }
  EXPECT_GT(checked, 30);
}

TEST(TetArap, RestAndRigidMotionGiveZero) {
  std::array<Eigen::Vector3d, 4> X = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 0, 1)};
  Eigen::Matrix3d Dm;
  for (int c = 0; c < 3; ++c) Dm.col(c) = X[c + 1] - X[0];
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::array<Eigen::Vector3d, 4> g;
  const double C = tet_arap_constraint(R * X[0] + Eigen::Vector3d(1, 2, 3), R * X[1] + Eigen::Vector3d(1, 2, 3),
                                       R * X[2] + Eigen::Vector3d(1, 2, 3), R * X[3] + Eigen::Vector3d(1, 2, 3), Dm.inverse(), &g);
  EXPECT_NEAR(C, 0, 1e-12);
  for (const auto& v : g) EXPECT_EQ(v.norm(), 0.0);  // the documented choice at C ≈ 0
  // Uniform stretch by 1.1: σ = (1.1, 1.1, 1.1), C = sqrt(3)·0.1.
  const double C2 = tet_arap_constraint(1.1 * X[0], 1.1 * X[1], 1.1 * X[2], 1.1 * X[3], Dm.inverse(), &g);
  EXPECT_NEAR(C2, std::sqrt(3.0) * 0.1, 1e-12);
}
