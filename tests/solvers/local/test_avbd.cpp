// Augmented VBD (solvers/local/avbd.hpp) on two particles with known solutions: a rigid distance
// (α = 0) — the multiplier update λ ← kC + λ and the ramp k ← k + βu|C|/l₀ checked after one sweep,
// then the iteration to the constrained minimiser x*, λ* = μ(|d̃| − l₀); a compliant one, where the
// augmented form reaches E's minimiser for any fixed k and the penalty form only once k reaches 1/α̃;
// and the ground as a hard inequality, which ends on the plane with the force that holds it.
#include "problems/problem.hpp"
#include "solvers/local/avbd.hpp"

#include <gtest/gtest.h>

using namespace xb;

namespace {

// Particles 0 and 1 (masses 1 and 3) joined by a distance of rest length 1, started at rest on it
// (x_t), predicted at x̃ = (0, 0, 0) and (2, 0.5, 0): stretched to |d̃| = √4.25.
struct Pair {
  Problem prob;
  Eigen::Matrix3Xd x_t, x_pred;
  Eigen::VectorXd alpha_tilde;
  double m0 = 1, m1 = 3, l0 = 1;
  explicit Pair(double alpha_tilde_value) {
    prob.particles.x = (Eigen::Matrix3Xd(3, 2) << 0, 1, 0, 0, 0, 0).finished();
    prob.particles.v = Eigen::Matrix3Xd::Zero(3, 2);
    prob.particles.w = (Eigen::VectorXd(2) << 1 / m0, 1 / m1).finished();
    prob.distance.idx = {{0, 1}};
    prob.distance.rest_length = {l0};
    prob.distance.compliance = {0};  // α̃ set directly below
    x_t = prob.particles.x;
    x_pred = (Eigen::Matrix3Xd(3, 2) << 0, 2, 0, 0.5, 0, 0).finished();
    alpha_tilde = Eigen::VectorXd::Constant(1, alpha_tilde_value);
  }
  double mu() const { return m0 * m1 / (m0 + m1); }
  double stretched() const { return (x_pred.col(1) - x_pred.col(0)).norm(); }
  // The minimiser at separation l along d̃, the centre of mass kept.
  Eigen::Matrix3Xd solution(double l) const {
    const Eigen::Vector3d d = (x_pred.col(1) - x_pred.col(0)).normalized();
    const Eigen::Vector3d c = (m0 * x_pred.col(0) + m1 * x_pred.col(1)) / (m0 + m1);
    Eigen::Matrix3Xd x(3, 2);
    x.col(0) = c - m1 / (m0 + m1) * l * d;
    x.col(1) = c + m0 / (m0 + m1) * l * d;
    return x;
  }
  double C(const Eigen::Matrix3Xd& x) const { return (x.col(1) - x.col(0)).norm() - l0; }
};

// Sweeps and dual updates as harness/sim/block_descent.cpp runs them.
void iterate(AugmentedVbd& avbd, const Pair& p, Eigen::Matrix3Xd& x, int n) {
  for (int it = 0; it < n; ++it) {
    avbd.sweep(x, p.x_pred);
    avbd.update_duals(x, Eigen::VectorXd::Constant(1, p.C(x)));
  }
}

}  // namespace

TEST(Avbd, RigidConstraintMultiplierUpdateAndSolution) {
  const Pair p(0.0);
  AvbdSettings s;
  s.stiffness_start = 2;
  s.beta = 10;
  const DualSystem ds(p.prob);
  AugmentedVbd avbd(p.prob, ds, s, p.alpha_tilde);
  avbd.begin_substep(p.x_t);  // C(x_t) = 0: no stabilisation term
  const double u = 1 / (1 / p.m0 + 1 / p.m1), k0 = s.stiffness_start * u;
  EXPECT_DOUBLE_EQ(avbd.stiffness(0), k0);
  EXPECT_EQ(avbd.lambda(0), 0);
  Eigen::Matrix3Xd x = p.x_pred;
  avbd.sweep(x, p.x_pred);
  const double C1 = p.C(x);
  avbd.update_duals(x, Eigen::VectorXd::Constant(1, C1));
  EXPECT_NEAR(avbd.lambda(0), k0 * C1, 1e-15 * k0);                        // λ ← kC + λ, from λ = 0
  EXPECT_NEAR(avbd.stiffness(0), k0 + s.beta * u * std::abs(C1) / p.l0, 1e-14);  // k ← k + βu|C|/l₀
  iterate(avbd, p, x, 200);
  EXPECT_LT((x - p.solution(p.l0)).norm(), 1e-10);
  EXPECT_NEAR(avbd.lambda(0), p.mu() * (p.stretched() - p.l0), 1e-9);  // the force that holds the pair at l₀
  Eigen::VectorXd lambda;
  avbd.multipliers(Eigen::VectorXd::Constant(1, p.C(x)), lambda);
  EXPECT_NEAR(lambda[0], -avbd.lambda(0), 1e-9);  // the records' sign: XPBD's
}

TEST(Avbd, CompliantAugmentedReachesTheMinimiserOfEForAnyStiffness) {
  const double at = 0.2;
  const Pair p(at);
  // E's minimiser: μ(|d̃| − l) = (l − l₀)/α̃.
  const double l = (p.mu() * p.stretched() + p.l0 / at) / (p.mu() + 1 / at);
  for (const std::string mode : {"augmented", "penalty"}) {
    AvbdSettings s;
    s.compliant = mode;
    s.beta = 0;               // no ramp: k stays at its start
    s.stiffness_start = 0.3;  // k = 0.3 u, far below 1/α̃ = 5
    const DualSystem ds(p.prob);
  AugmentedVbd avbd(p.prob, ds, s, p.alpha_tilde);
    avbd.begin_substep(p.x_t);
    Eigen::Matrix3Xd x = p.x_pred;
    iterate(avbd, p, x, 300);
    const double err = (x - p.solution(l)).norm();
    if (mode == "augmented") {
      EXPECT_LT(err, 1e-10);
      EXPECT_NEAR(avbd.lambda(0), (l - p.l0) / at, 1e-9);
    } else {
      EXPECT_GT(err, 1e-2) << "the penalty form at k << 1/alpha~ minimises a softer energy";
    }
  }
  AvbdSettings ramp;  // penalty with the ramp: k climbs to 1/α̃ and the answer is E's
  ramp.compliant = "penalty";
  ramp.beta = 1e3;
  const DualSystem ds(p.prob);
  AugmentedVbd avbd(p.prob, ds, ramp, p.alpha_tilde);
  avbd.begin_substep(p.x_t);
  Eigen::Matrix3Xd x = p.x_pred;
  iterate(avbd, p, x, 300);
  EXPECT_DOUBLE_EQ(avbd.stiffness(0), 1 / at);
  EXPECT_LT((x - p.solution(l)).norm(), 1e-10);
}

TEST(Avbd, GroundIsAHardInequality) {
  // The pair lying along x at rest, predicted 1 cm below the ground y = 0: it ends on the plane,
  // each particle held by the ground's force m(ỹ − 0) (AVBD's sign: negative pushes up).
  Pair p(1e-3);
  p.prob.planes.push_back({0.0});
  p.x_t = p.prob.particles.x;
  p.x_pred = p.x_t;
  p.x_pred.row(1).setConstant(-0.01);
  const DualSystem ds(p.prob);
  AugmentedVbd avbd(p.prob, ds, AvbdSettings{}, p.alpha_tilde);
  avbd.begin_substep(p.x_t);
  Eigen::Matrix3Xd x = p.x_pred;
  iterate(avbd, p, x, 100);
  EXPECT_LT(x.row(1).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(avbd.ground_lambda(0), p.m0 * -0.01, 1e-12);
  EXPECT_NEAR(avbd.ground_lambda(1), p.m1 * -0.01, 1e-12);
  EXPECT_EQ(avbd.statistics().at("ground_contacts"), 2);
}
