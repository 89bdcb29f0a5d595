// Vertex Block Descent (solvers/local/vbd.hpp) against an independent per-vertex Newton: on a tiny
// tet bar and a tiny cloth, vertex by vertex in the sweep's order, the gradient of h²E from the
// constraints' own gradients (primal_residual_vector), its 3×3 block of the Hessian by central
// differences of that gradient, and a dense 3×3 solve; with clamp on a compressed mesh, the blocks
// of the whole-element projected Hessians instead. Also: sweeps converge to ∇E = 0, the Chebyshev
// iterate is the paper's combination of plain sweeps, and the ground penalty's one-particle answer.
#include "harness/sim/newton.hpp"
#include "problems/constraint_hessian.hpp"
#include "problems/scene.hpp"
#include "solvers/local/vbd.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {

struct Case {
  Problem prob;
  Eigen::VectorXd alpha_tilde;
  Eigen::Matrix3Xd x, x_pred;
  double h = 1e-2;
};

// A scene stretched by `stretch` about its first particle, and x̃ a random offset of it.
Case make_case(const std::string& scene, double stretch, double compliance) {
  SceneSettings s;
  s.scene = scene;
  s.resolution = scene == "cloth_hang" ? 3 : 1;
  s.aspect = 2;
  Case c{build_problem(s), {}, {}, {}};
  for (auto& a : c.prob.distance.compliance) a = compliance;
  for (auto& a : c.prob.tets.compliance) a = compliance;
  c.alpha_tilde = scaled_compliance(c.prob, c.h);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  c.x = c.prob.particles.x;
  const Eigen::Vector3d o = c.x.col(0);
  for (int i = 0; i < c.x.cols(); ++i) c.x.col(i) = o + stretch * (c.x.col(i) - o);
  c.x_pred = c.x;
  for (int i = 0; i < c.x.cols(); ++i)
    if (c.prob.particles.w[i] > 0) c.x_pred.col(i) += 0.02 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  for (int i = 0; i < c.x.cols(); ++i)
    if (c.prob.particles.w[i] == 0) c.x.col(i) = c.x_pred.col(i);
  return c;
}

// h²∇E at x from the constraints' gradients (harness/sim/newton.hpp), not from vertex_derivatives.
Eigen::Matrix3Xd gradient(const Case& c, const DualSystem& ds, const Eigen::Matrix3Xd& x) {
  ConstraintState s;
  evaluate_constraints(c.prob, x, s, newton_rest_epsilon);
  Eigen::VectorXd lambda;
  eliminate_multipliers(s, c.alpha_tilde, lambda);
  Eigen::Matrix3Xd g;
  primal_residual_vector(c.prob, ds, s, x, c.x_pred, lambda, g);
  return g;
}

// One Gauss–Seidel sweep of per-vertex Newton steps in the colouring's order; `block` gives vertex
// i's 3×3 Hessian block at x.
template <class Block>
Eigen::Matrix3Xd reference_sweep(const Case& c, const DualSystem& ds, Eigen::Matrix3Xd x, Block&& block) {
  const Coloring col = free_vertex_coloring(c.prob);
  for (int i : col.order) {
    const Eigen::Vector3d g = gradient(c, ds, x).col(i);
    const Eigen::Matrix3d H = block(x, i);
    x.col(i) -= H.fullPivLu().solve(g);  // the dense 3×3 solve
  }
  return x;
}

// Vertex i's block of h²∇²E by central differences of the gradient.
Eigen::Matrix3d fd_block(const Case& c, const DualSystem& ds, const Eigen::Matrix3Xd& x, int i) {
  Eigen::Matrix3d H;
  const double eps = 1e-6;
  for (int d = 0; d < 3; ++d) {
    Eigen::Matrix3Xd xp = x, xm = x;
    xp(d, i) += eps;
    xm(d, i) -= eps;
    H.col(d) = (gradient(c, ds, xp).col(i) - gradient(c, ds, xm).col(i)) / (2 * eps);
  }
  return 0.5 * (H + H.transpose());
}

Eigen::Matrix3Xd vbd_sweeps(const Case& c, const DualSystem& ds, const VbdSettings& s, int sweeps) {
  VertexBlockDescent vbd(c.prob, ds, s, c.alpha_tilde, c.h);
  Eigen::Matrix3Xd x = c.x;
  vbd.begin_substep(x);
  for (int k = 0; k < sweeps; ++k) vbd.iterate(x, c.x_pred);
  return x;
}

double scale(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) { return (a - b).cwiseAbs().maxCoeff(); }

}  // namespace

TEST(Vbd, OneSweepIsPerVertexNewtonWithDenseSolves) {
  for (const std::string scene : {"twist_bar", "cloth_hang"}) {
    const Case c = make_case(scene, 1.2, 1e-6);  // stretched: every element's vertex block is PD, none = exact
    const DualSystem ds(c.prob);
    VbdSettings s;
    s.projection = "none";
    const Eigen::Matrix3Xd got = vbd_sweeps(c, ds, s, 1);
    const Eigen::Matrix3Xd want = reference_sweep(c, ds, c.x, [&](const Eigen::Matrix3Xd& x, int i) {
      return fd_block(c, ds, x, i);
    });
    EXPECT_LT(scale(got, want), 1e-6 * scale(want, c.x)) << scene;
    EXPECT_GT(scale(want, c.x), 1e-4) << scene << ": the sweep should move the vertices";
  }
}

TEST(Vbd, ClampTakesTheBlocksOfTheProjectedElementHessians) {
  const Case c = make_case("twist_bar", 0.4, 1e-6);  // compressed: indefinite twist modes
  const DualSystem ds(c.prob);
  const Eigen::Matrix3Xd got = vbd_sweeps(c, ds, VbdSettings{}, 1);
  const Eigen::Matrix3Xd want = reference_sweep(c, ds, c.x, [&](const Eigen::Matrix3Xd& x, int i) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Identity() / c.prob.particles.w[i];
    for (int t = 0; t < static_cast<int>(c.prob.tets.size()); ++t) {
      const auto& e = c.prob.tets.idx[t];
      const Matrix12d Ht = tet_energy_hessian(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), c.prob.tets.Dm_inv[t],
                                              c.alpha_tilde[t], Projection::clamp);
      for (int a = 0; a < 4; ++a)
        if (e[a] == i) H += Ht.block<3, 3>(3 * a, 3 * a);
    }
    return H;
  });
  EXPECT_LT(scale(got, want), 1e-9 * scale(want, c.x));
}

TEST(Vbd, SweepsConvergeToTheMinimiserOfE) {
  const Case c = make_case("cloth_hang", 1.05, 1e-4);
  const DualSystem ds(c.prob);
  const double g0 = gradient(c, ds, c.x).norm();
  const Eigen::Matrix3Xd x = vbd_sweeps(c, ds, VbdSettings{}, 400);
  EXPECT_LT(gradient(c, ds, x).norm(), 1e-10 * g0);
}

TEST(Vbd, ChebyshevCombinesPlainSweepsAsThePaper) {
  const Case c = make_case("twist_bar", 1.1, 1e-6);
  const DualSystem ds(c.prob);
  VbdSettings accel;
  accel.acceleration = "chebyshev";
  accel.rho = 0.9;
  const Eigen::Matrix3Xd got = vbd_sweeps(c, ds, accel, 3);
  VertexBlockDescent plain(c.prob, ds, VbdSettings{}, c.alpha_tilde, c.h);
  plain.begin_substep(c.x);
  auto S = [&](Eigen::Matrix3Xd x) {
    plain.iterate(x, c.x_pred);
    return x;
  };
  const double r2 = 0.81, w2 = 2 / (2 - r2), w3 = 4 / (4 - r2 * w2);
  const Eigen::Matrix3Xd x0 = c.x, x1 = S(x0), x2 = w2 * (S(x1) - x0) + x0, x3 = w3 * (S(x2) - x1) + x1;
  EXPECT_LT(scale(got, x3), 1e-12 * scale(x3, x0));
}

TEST(Vbd, GroundPenaltyLeavesThePenetrationOfItsStiffness) {
  // Two free particles (no constraint), both predicted 1 cm below the ground y = 0: each settles where
  // m(y − ỹ) + k_c y = 0, y = ỹ/(1 + κ_c), in one sweep (the energy is quadratic in y).
  Problem prob;
  prob.particles.x = (Eigen::Matrix3Xd(3, 2) << 0, 1, 0.001, 0.001, 0, 0).finished();
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 2);
  prob.particles.w = (Eigen::VectorXd(2) << 1.0, 0.5).finished();
  prob.planes.push_back({0.0});
  const Eigen::VectorXd at = scaled_compliance(prob, 1e-2);
  const DualSystem ds(prob);
  VbdSettings s;
  s.contact_stiffness = 1e3;
  VertexBlockDescent vbd(prob, ds, s, at, 1e-2);
  Eigen::Matrix3Xd x_pred = prob.particles.x;
  x_pred.row(1).setConstant(-0.01);
  Eigen::Matrix3Xd x = x_pred;
  vbd.begin_substep(prob.particles.x);
  vbd.iterate(x, x_pred);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(x(1, i), -0.01 / (1 + 1e3), 1e-16) << i;
  EXPECT_EQ(x.row(0), x_pred.row(0));
}
