// One constraint seen from one particle (problems/vertex_derivatives.hpp): the gradient against
// central differences of C, the exact energy block against central differences of C∇_aC (the
// gradient of ½C²), the curvature block against differences of ∇_aC, and both projected blocks
// against the (a, a) blocks of the whole-element Hessians of problems/constraint_hessian.hpp — on
// stretched, compressed, inverted and randomly posed tets and distances.
#include "problems/constraint_hessian.hpp"
#include "problems/constraints.hpp"
#include "problems/vertex_derivatives.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {

std::mt19937 rng(11);
double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
Eigen::Vector3d rand3(double s) { return {uni(-s, s), uni(-s, s), uni(-s, s)}; }

// One tet (constraint 1) and one distance (constraint 0) sharing particle 0; every particle free.
Problem two_elements(const Eigen::Matrix3d& F) {
  Problem p;
  std::array<Eigen::Vector3d, 4> X = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0), Eigen::Vector3d(0.2, 1, 0),
                                      Eigen::Vector3d(0, 0.1, 1)};
  Eigen::Matrix3d Dm;
  for (int c = 0; c < 3; ++c) Dm.col(c) = X[c + 1] - X[0];
  p.particles.x.resize(3, 5);
  for (int a = 0; a < 4; ++a) p.particles.x.col(a) = F * X[a] + rand3(0.05);
  p.particles.x.col(4) = p.particles.x.col(0) + Eigen::Vector3d(0.7, 0.2, -0.3);
  p.particles.v = Eigen::Matrix3Xd::Zero(3, 5);
  p.particles.w = Eigen::VectorXd::Ones(5);
  p.distance.idx = {{0, 4}};
  p.distance.rest_length = {0.5};
  p.distance.compliance = {1e-3};
  p.tets.idx = {{0, 1, 2, 3}};
  p.tets.Dm_inv = {Dm.inverse()};
  p.tets.rest_volume = {Dm.determinant() / 6};
  p.tets.compliance = {1e-3};
  return p;
}

// C and particle a's gradient of constraint j at x (Newton's rest_epsilon = 0).
double value(const Problem& p, const Eigen::Matrix3Xd& x, int j, int a, Eigen::Vector3d* grad) {
  ConstraintState s;
  evaluate_constraints(p, x, s, 0.0);
  if (grad) *grad = s.grad[j][a];
  return s.C[j];
}

void check_against_differences(const Problem& p, int j, int a) {
  const Eigen::Matrix3Xd& x = p.particles.x;
  const int particle = p.constraint_particles(j)[a];
  const VertexDerivatives d = vertex_derivatives(p, x, j, a, Projection::none, true);
  const double eps = 1e-6;
  Eigen::Matrix3d energy_fd, curvature_fd;
  Eigen::Vector3d grad_fd;
  for (int c = 0; c < 3; ++c) {
    Eigen::Matrix3Xd xp = x, xm = x;
    xp(c, particle) += eps;
    xm(c, particle) -= eps;
    Eigen::Vector3d gp, gm;
    const double Cp = value(p, xp, j, a, &gp), Cm = value(p, xm, j, a, &gm);
    grad_fd[c] = (Cp - Cm) / (2 * eps);
    energy_fd.col(c) = (Cp * gp - Cm * gm) / (2 * eps);  // ∂(C∇_aC)/∂x_a
    curvature_fd.col(c) = (gp - gm) / (2 * eps);
  }
  EXPECT_NEAR(d.C, value(p, x, j, a, nullptr), 1e-14);
  EXPECT_LT((d.grad - grad_fd).norm(), 1e-7 * (1 + grad_fd.norm())) << "constraint " << j << " slot " << a;
  EXPECT_LT((d.energy - energy_fd).norm(), 1e-6 * (1 + energy_fd.norm())) << "constraint " << j << " slot " << a;
  EXPECT_LT((d.curvature - curvature_fd).norm(), 1e-5 * (1 + curvature_fd.norm())) << "constraint " << j << " slot " << a;
}

}  // namespace

TEST(VertexDerivatives, MatchFiniteDifferences) {
  const std::vector<Eigen::Vector3d> stretches = {{1.3, 1.1, 0.9}, {0.6, 0.5, 0.4}, {1.2, 0.8, -0.3}};
  for (const Eigen::Vector3d& s : stretches) {
    const Eigen::Matrix3d F = Eigen::AngleAxisd(uni(0, 3), rand3(1).normalized()).toRotationMatrix() * s.asDiagonal();
    const Problem p = two_elements(F);
    for (int a = 0; a < 2; ++a) check_against_differences(p, 0, a);
    for (int a = 0; a < 4; ++a) check_against_differences(p, 1, a);
  }
}

// The projected energy block is the (a, a) block of the whole element's projected Hessian (times
// α̃), and the curvature block that of ∇²C: the closed forms without the 12×12.
TEST(VertexDerivatives, BlocksOfTheElementHessians) {
  const double alpha = 0.25;
  for (const Eigen::Vector3d& s : {Eigen::Vector3d(0.3, 0.2, -0.1), Eigen::Vector3d(1.4, 1.2, 1.1)}) {
    const Problem p = two_elements(s.asDiagonal());
    const Eigen::Matrix3Xd& x = p.particles.x;
    const auto& e = p.tets.idx[0];
    for (const Projection proj : {Projection::none, Projection::clamp, Projection::abs}) {
      const Matrix12d H = tet_energy_hessian(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), p.tets.Dm_inv[0], alpha, proj);
      const Matrix6d Hd = distance_energy_hessian(x.col(0), x.col(4), 0.5, alpha, proj);
      for (int a = 0; a < 4; ++a) {
        const VertexDerivatives d = vertex_derivatives(p, x, 1, a, proj, false);
        EXPECT_LT((d.energy / alpha - H.block<3, 3>(3 * a, 3 * a)).norm(), 1e-9 * H.norm()) << a;
      }
      for (int a = 0; a < 2; ++a) {
        const VertexDerivatives d = vertex_derivatives(p, x, 0, a, proj, false);
        EXPECT_LT((d.energy / alpha - Hd.block<3, 3>(3 * a, 3 * a)).norm(), 1e-12 * Hd.norm()) << a;
      }
    }
    const Matrix12d K = tet_arap_hessian(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), p.tets.Dm_inv[0]);
    for (int a = 0; a < 4; ++a)
      EXPECT_LT((vertex_derivatives(p, x, 1, a, Projection::none, true).curvature - K.block<3, 3>(3 * a, 3 * a)).norm(),
                1e-9 * K.norm());
  }
}

// Compressed: the clamped block is PSD where the exact one is not.
TEST(VertexDerivatives, ClampMakesTheBlockPositiveSemiDefinite) {
  const Problem p = two_elements(Eigen::Vector3d(0.3, 0.25, 0.2).asDiagonal());
  bool indefinite = false;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Matrix3d exact = vertex_derivatives(p, p.particles.x, 1, a, Projection::none, false).energy;
    const Eigen::Matrix3d clamped = vertex_derivatives(p, p.particles.x, 1, a, Projection::clamp, false).energy;
    indefinite |= Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(exact).eigenvalues().minCoeff() < -1e-9;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(clamped).eigenvalues().minCoeff(), -1e-12);
  }
  EXPECT_TRUE(indefinite) << "the compressed tet should have an indefinite vertex block";
}
