// The primal form K Δx = Jᵀα̃⁻¹b against the dual system it replaces: K against an independent
// sparse product, Δλ against the dual CHOLMOD solution, the residual identity, the rigid modes,
// the refusal at zero compliance, and the Jacobian's round trip through its CSR form.
#include "harness/sim/primal_solve.hpp"
#include "harness/io/system_io.hpp"
#include "problems/dual_system.hpp"
#include "core/error.hpp"
#include "harness/params.hpp"
#include "problems/primal_system.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {

struct Case {
  Problem prob;
  ConstraintState s;
  Eigen::VectorXd alpha_tilde;
};

// A scene with its positions perturbed (every constraint active), its constraints evaluated.
Case make_case(const std::string& scene, const std::vector<std::pair<std::string, std::string>>& sets) {
  Params p;
  p.scene = scene;
  for (const auto& [k, v] : sets) set_param(p, k, v, "test");
  Case c{build_problem(p), {}, {}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < c.prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) c.prob.particles.x(d, i) += 0.01 * p.size / p.resolution * u(rng);
  evaluate_constraints(c.prob, c.prob.particles.x, c.s);
  c.alpha_tilde = scaled_compliance(c.prob, p.dt);
  return c;
}

// J over the free particles (m × 3·free) as an Eigen sparse matrix, built independently.
SparseMatrix free_jacobian(const Case& c, const PrimalSystem& ps) {
  std::vector<int> block(c.prob.particles.size(), -1);
  for (size_t i = 0; i < ps.free_particles().size(); ++i) block[ps.free_particles()[i]] = static_cast<int>(i);
  std::vector<Eigen::Triplet<double, int>> t;
  for (int j = 0; j < c.prob.num_constraints(); ++j) {
    const auto pj = c.prob.constraint_particles(j);
    for (int k = 0; k < 4; ++k)
      if (pj[k] >= 0 && block[pj[k]] >= 0)
        for (int d = 0; d < 3; ++d) t.emplace_back(j, 3 * block[pj[k]] + d, c.s.grad[j][k][d]);
  }
  SparseMatrix J(c.prob.num_constraints(), ps.rows());
  J.setFromTriplets(t.begin(), t.end());
  return J;
}

void expect_primal_matches_dual(const Case& c) {
  PrimalSystem ps(constraint_graph(c.prob));
  ps.fill(c.s.grad, c.alpha_tilde);
  const int m = c.prob.num_constraints();

  // K = M + Jᵀ α̃⁻¹ J by an independent sparse product.
  const SparseMatrix J = free_jacobian(c, ps);
  Eigen::VectorXd mass(ps.rows());
  for (size_t i = 0; i < ps.free_particles().size(); ++i)
    mass.segment<3>(3 * i).setConstant(1.0 / c.prob.particles.w[ps.free_particles()[i]]);
  SparseMatrix Kref = SparseMatrix(J.transpose()) * c.alpha_tilde.cwiseInverse().asDiagonal() * J;
  Kref.diagonal() += mass;
  const double kscale = Eigen::MatrixXd(Kref).cwiseAbs().maxCoeff();
  EXPECT_LE((Eigen::MatrixXd(ps.K()) - Eigen::MatrixXd(Kref)).cwiseAbs().maxCoeff(), 1e-12 * kscale);

  // Δλ from the primal form (dense solve of K) equals the dual CHOLMOD solution.
  DualSystem ds(c.prob);
  ds.fill(c.s, c.alpha_tilde);
  const Vector b = -c.s.C;
  Params p;
  auto chol = make_linear_solver("cholmod", p);
  chol->setup(ds.A(), SetupKind::Structure, SetupContext{});
  Vector dl_dual;
  ASSERT_EQ(chol->solve(b, dl_dual).status, LinearStatus::converged);
  Vector f, dl_primal;
  ps.rhs(c.s.grad, c.alpha_tilde, b, f);
  const Vector dx = Eigen::MatrixXd(ps.K()).llt().solve(f);
  ps.recover(c.s.grad, c.alpha_tilde, b, dx, dl_primal);
  EXPECT_LE((dl_primal - dl_dual).norm(), 1e-8 * dl_dual.norm());

  // The same through PrimalSolve with an iterative solver judged on the dual residual. (Tighter
  // than 1e-8 the recovery Δλ = α̃⁻¹(b − JΔx) loses digits to cancellation on stiff systems: at
  // 1e-10 the stiff bar's recomputed residual was 4e-10.)
  p.linear.tol = 1e-8;
  p.linear.max_iterations = 100000;
  PrimalSolve solve(make_linear_solver("jacobi-pcg", p), constraint_graph(c.prob), p.linear);
  solve.setup(c.s.grad, c.alpha_tilde, c.prob.particles.x, SetupKind::Structure, SetupContext{});
  Vector dl_iter;
  const LinearStats st = solve.solve(b, dl_iter);
  EXPECT_EQ(st.status, LinearStatus::converged) << st.iterations << " iterations, " << st.final_relative_residual;
  Vector r = b - ds.A() * dl_iter;
  EXPECT_LE(r.norm(), 1.2e-8 * b.norm());
  EXPECT_NEAR(st.final_relative_residual, r.norm() / b.norm(), 0.2 * r.norm() / b.norm());
  EXPECT_LE((dl_iter - dl_dual).norm(), 1e-5 * dl_dual.norm());

  // The identity b − AΔλ = −J M⁻¹ r_K for any Δx, not only the solution.
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Vector dx_any(ps.rows());
  for (long i = 0; i < dx_any.size(); ++i) dx_any[i] = dx[i] * (1 + 0.1 * g(rng));
  Vector dl_any, dual_res;
  ps.recover(c.s.grad, c.alpha_tilde, b, dx_any, dl_any);
  const Vector r_K = f - ps.K() * dx_any;
  ps.dual_residual(c.s.grad, r_K, dual_res);
  const Vector direct = b - ds.A() * dl_any;
  EXPECT_LE((dual_res - direct).norm(), 1e-9 * direct.norm());
  EXPECT_EQ(m, dual_res.size());
}

}  // namespace

TEST(PrimalSystem, ClothWithPinsMatchesDual) {
  expect_primal_matches_dual(make_case("cloth_hang", {{"resolution", "6"}}));
}

TEST(PrimalSystem, TetArapBarMatchesDual) {
  expect_primal_matches_dual(make_case("bar_hang", {{"resolution", "2"}, {"prestretch", "1.05"}}));
}

TEST(PrimalSystem, StiffSquashMatchesDual) {
  expect_primal_matches_dual(make_case("bar_hang", {{"resolution", "2"}, {"stiffness", "1e9"}, {"dt", "0.01"}}));
}

TEST(PrimalSystem, RigidModesSpanTheKernelOfTheConstraintPart) {
  for (const std::string scene : {"cloth_hang", "bar_hang"}) {
    Case c = make_case(scene, {{"resolution", "3"}});
    c.prob.particles.w.setOnes();  // unpinned: the rigid motions are exact kernel vectors of Jᵀα̃⁻¹J
    PrimalSystem ps(constraint_graph(c.prob));
    ps.fill(c.s.grad, c.alpha_tilde);
    SparseMatrix KminusM = ps.K();
    for (int i = 0; i < ps.rows(); ++i) KminusM.coeffRef(i, i) -= 1.0;
    const Eigen::MatrixXd B = ps.rigid_modes(c.prob.particles.x);
    ASSERT_EQ(B.cols(), 6);
    const double scale = Eigen::MatrixXd(KminusM).norm() * B.norm();
    EXPECT_LE((KminusM * B).norm(), 1e-10 * scale) << scene;
    // ... and they are independent: a rank-6 basis.
    EXPECT_EQ(Eigen::FullPivLU<Eigen::MatrixXd>(B).rank(), 6) << scene;
  }
}

TEST(PrimalSystem, FormResolution) {
  Eigen::VectorXd soft = Eigen::VectorXd::Constant(4, 1e-6), rigid = soft;
  rigid[2] = 0;
  EXPECT_EQ(resolve_form("auto", soft), "primal");
  EXPECT_EQ(resolve_form("auto", rigid), "dual");
  EXPECT_EQ(resolve_form("dual", soft), "dual");
  EXPECT_EQ(resolve_form("primal", soft), "primal");
  try {
    resolve_form("primal", rigid);
    FAIL() << "form=primal with a rigid constraint was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("1 of 4 constraints have compliance 0"), std::string::npos) << e.what();
  }
}

TEST(PrimalSystem, JacobianRoundTripsThroughCsr) {
  const Case c = make_case("bar_hang", {{"resolution", "2"}});
  const ConstraintGraph graph = constraint_graph(c.prob);
  const SparseMatrix J = jacobian_csr(graph, c.s.grad);
  EXPECT_EQ(J.rows(), c.prob.num_constraints());
  EXPECT_EQ(J.cols(), 3 * c.prob.particles.size());
  ConstraintGraph back;
  Gradients grad;
  jacobian_from_csr(J, back, grad);
  back.w = graph.w;
  // Slots may be reordered (ascending particle), so compare K, which does not depend on the order.
  PrimalSystem a(graph), b(back);
  a.fill(c.s.grad, c.alpha_tilde);
  b.fill(grad, c.alpha_tilde);
  EXPECT_EQ((Eigen::MatrixXd(a.K()) - Eigen::MatrixXd(b.K())).cwiseAbs().maxCoeff(), 0.0);
}

TEST(PrimalSystem, KIsExactlySymmetricAndRefillsRepeat) {
  const Case c = make_case("bar_hang", {{"resolution", "2"}, {"prestretch", "1.05"}});
  PrimalSystem ps(constraint_graph(c.prob));
  ps.fill(c.s.grad, c.alpha_tilde);
  const Eigen::MatrixXd K(ps.K());
  EXPECT_EQ(K, K.transpose());  // block (q, p) is block (p, q) transposed, bit for bit
  Eigen::VectorXd other = 2 * c.alpha_tilde;
  ps.fill(c.s.grad, other);
  EXPECT_NE(Eigen::MatrixXd(ps.K()), K);
  ps.fill(c.s.grad, c.alpha_tilde);
  EXPECT_EQ(Eigen::MatrixXd(ps.K()), K);
}
