// The assembled dual system against a dense J M⁻¹ Jᵀ + α̃, with pins.
#include "problems/dual_system.hpp"
#include "problems/meshes/generators.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {
// Dense J (m × 3n) from a constraint state.
Eigen::MatrixXd dense_jacobian(const Problem& prob, const ConstraintState& s) {
  const int m = prob.num_constraints(), n = prob.particles.size();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, 3 * n);
  for (int j = 0; j < m; ++j) {
    const auto ps = prob.constraint_particles(j);
    for (int k = 0; k < 4; ++k)
      if (ps[k] >= 0) J.block<1, 3>(j, 3 * ps[k]) += s.grad[j][k].transpose();
  }
  return J;
}

void check_against_dense(Problem prob, double dt) {
  // Perturb positions so that every constraint is active (C ≠ 0, gradients defined).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (int i = 0; i < prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) prob.particles.x(d, i) += u(rng) * 0.1;
  DualSystem ds(prob);
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  const Eigen::VectorXd at = scaled_compliance(prob, dt);
  ds.fill(s, at);
  const Eigen::MatrixXd J = dense_jacobian(prob, s);
  Eigen::VectorXd minv(3 * prob.particles.size());
  for (int i = 0; i < prob.particles.size(); ++i) minv.segment<3>(3 * i).setConstant(prob.particles.w[i]);
  Eigen::MatrixXd Aref = J * minv.asDiagonal() * J.transpose();
  Aref.diagonal() += at;
  const Eigen::MatrixXd A = Eigen::MatrixXd(ds.A());
  EXPECT_LE((A - Aref).cwiseAbs().maxCoeff(), 1e-12 * Aref.cwiseAbs().maxCoeff());
  // The pattern has no entry where the dense matrix is structurally zero because of pins:
  // rows coupled only through a pinned particle are not stored.
  int stored_zero = 0;
  for (int k = 0; k < ds.A().outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(ds.A(), k); it; ++it)
      if (it.row() != it.col() && Aref(it.row(), it.col()) == 0) ++stored_zero;
  EXPECT_EQ(stored_zero, 0);
  // Δx = M⁻¹ ∇Cᵀ y.
  Eigen::VectorXd y = Eigen::VectorXd::Random(prob.num_constraints());
  Eigen::Matrix3Xd dx;
  ds.apply_minv_gradT(s, y, dx);
  const Eigen::VectorXd ref = minv.asDiagonal() * (J.transpose() * y);
  EXPECT_LE((Eigen::Map<const Eigen::VectorXd>(dx.data(), dx.size()) - ref).norm(), 1e-12 * ref.norm());
}

// Three particles at (x_i, y_i, z_i) with inverse masses w, joined by two unit-length distance
// constraints (0–1, 1–2) of compliance c01 and c12.
Problem chain3(const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z, const Eigen::Vector3d& w,
               double c01, double c12) {
  Problem prob;
  prob.name = "chain of three";
  prob.particles.x.resize(3, 3);
  prob.particles.x << x.transpose(), y.transpose(), z.transpose();
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 3);
  prob.particles.w = w;
  prob.distance.idx = {{0, 1}, {1, 2}};
  prob.distance.rest_length = {1, 1};
  prob.distance.compliance = {c01, c12};
  return prob;
}
}  // namespace

TEST(DualSystem, ClothMatchesDenseWithPins) {
  Params p;
  p.scene = "cloth_hang";
  p.resolution = 5;
  Problem prob = build_problem(p);
  int pinned = 0;
  for (int i = 0; i < prob.particles.size(); ++i) pinned += prob.particles.w[i] == 0;
  ASSERT_EQ(pinned, 2);
  ASSERT_EQ(prob.num_constraints(), 2 * 5 * 6 + 25);  // NE = 2N(N+1) + N²
  check_against_dense(prob, 3e-3);
}

TEST(DualSystem, TetBarMatchesDenseWithPinsAndMassRatio) {
  Params p;
  p.scene = "bar_hang";
  p.resolution = 2;
  p.aspect = 2;
  p.size = 0.2;
  p.stiffness = 1e6;
  Problem prob = build_problem(p);
  ASSERT_EQ(prob.num_constraints(), 6 * 4 * 2 * 2);
  for (int i = 0; i < prob.particles.size(); ++i)
    if (prob.particles.w[i] > 0) prob.particles.w[i] = 1.0 / (1.0 + i);  // unequal masses
  check_against_dense(prob, 1e-2);
}

TEST(DualSystem, PinnedParticlesCoupleNothing) {
  // Two distance constraints sharing only a pinned particle are not coupled.
  Problem prob =
      chain3(Eigen::Vector3d(0, 1, 2), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 1), 0, 0);
  DualSystem ds(prob);
  EXPECT_EQ(ds.A().nonZeros(), 2);
  prob.particles.w[1] = 1;
  DualSystem ds2(prob);
  EXPECT_EQ(ds2.A().nonZeros(), 4);
}

TEST(DualSystem, RowOfPinnedParticlesIsAlphaAloneAndRefillsRepeat) {
  // Constraint 0 joins two pinned particles: its row is α̃ alone. Constraint 1 has one free particle.
  const Problem prob = chain3(Eigen::Vector3d(0, 1, 2), Eigen::Vector3d(0, 0.5, 0), Eigen::Vector3d(0, 0, 0.3),
                              Eigen::Vector3d(0, 0, 0.5), 1e-3, 2e-3);
  DualSystem ds(prob);
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  const Eigen::VectorXd at = Eigen::Vector2d(3.0, 5.0);
  ds.fill(s, at);
  ASSERT_EQ(ds.A().nonZeros(), 2);
  const Eigen::MatrixXd A(ds.A());
  EXPECT_EQ(A(0, 0), 3.0);
  EXPECT_DOUBLE_EQ(A(1, 1), 0.5 * s.grad[1][1].squaredNorm() + 5.0);
  // A fill overwrites every value: other gradients, then the first ones again, give the first A.
  ConstraintState other = s;
  for (auto& g : other.grad)
    for (auto& v : g) v *= 3;
  ds.fill(other, at);
  EXPECT_NE(Eigen::MatrixXd(ds.A()), A);
  ds.fill(s, at);
  EXPECT_EQ(Eigen::MatrixXd(ds.A()), A);
}
