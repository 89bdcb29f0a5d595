// The linear step with XPBD's two simplifications switched off (harness/sim/global_step.hpp)
// against a dense solve of the KKT system of Eq. 5–6 whose top-left block is M − Σλ_j∇²C_j, that
// Hessian taken by central differences of ∇Cᵀλ (independent of the analytic element Hessians).
#include "harness/params.hpp"
#include "harness/sim/global_step.hpp"
#include "harness/sim/newton.hpp"
#include "core/error.hpp"
#include "problems/scene.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;

namespace {
// A bar (or cloth) with pins, stretched by 10% with a little noise: every tet's singular
// values > 1 and every multiplier λ = −0.7 α̃⁻¹C < 0 (not XPBD's or Newton's own λ), so each
// −λ_j∇²C_j is PSD and the projection changes nothing: the dense KKT solve is the reference.
struct Case {
  Params p;
  Problem prob;
  ConstraintState s;
  Eigen::VectorXd alpha_tilde, lambda;
  Eigen::Matrix3Xd x_pred;
};

Case stretched_bar(const std::string& scene) {
  Case c;
  c.p.scene = scene;
  c.p.resolution = 2;
  c.p.aspect = 2;
  c.p.stiffness = 1e6;
  c.prob = build_problem(c.p);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix3Xd& x = c.prob.particles.x;
  x *= 1.1;
  for (int i = 0; i < x.cols(); ++i)
    if (c.prob.particles.w[i] > 0)
      for (int d = 0; d < 3; ++d) x(d, i) += 1e-3 * c.p.size * u(rng);
  for (int i = 0; i < x.cols(); ++i)
    if (c.prob.particles.w[i] > 0) c.prob.particles.w[i] *= 1 + 0.5 * u(rng);  // uneven masses
  c.x_pred = x;
  for (int i = 0; i < x.cols(); ++i)
    if (c.prob.particles.w[i] > 0) c.x_pred.col(i) += 1e-3 * c.p.size * Eigen::Vector3d(u(rng), u(rng), u(rng));
  evaluate_constraints(c.prob, x, c.s);
  c.alpha_tilde = scaled_compliance(c.prob, c.p.dt);
  c.lambda = -0.7 * c.s.C.cwiseQuotient(c.alpha_tilde);
  return c;
}

// Dense J (m × 3n, all particles) and ∂(∇Cᵀλ)/∂x by central differences.
Eigen::MatrixXd dense_J(const Case& c) {
  const int n = c.prob.particles.size(), m = c.prob.num_constraints();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, 3 * n);
  for (int j = 0; j < m; ++j) {
    const auto ps = c.prob.constraint_particles(j);
    for (int a = 0; a < 4; ++a)
      if (ps[a] >= 0) J.block(j, 3 * ps[a], 1, 3) += c.s.grad[j][a].transpose();
  }
  return J;
}

Eigen::MatrixXd lambda_hessian_fd(const Case& c) {
  const int n = c.prob.particles.size();
  DualSystem ds(c.prob);
  Eigen::MatrixXd H(3 * n, 3 * n);
  const double eps = 1e-6 * c.p.size;
  ConstraintState s;
  Eigen::Matrix3Xd x = c.prob.particles.x, fp, fm;
  for (int k = 0; k < 3 * n; ++k) {
    x(k % 3, k / 3) += eps;
    evaluate_constraints(c.prob, x, s);
    ds.apply_gradT(s, c.lambda, fp);
    x(k % 3, k / 3) -= 2 * eps;
    evaluate_constraints(c.prob, x, s);
    ds.apply_gradT(s, c.lambda, fm);
    x(k % 3, k / 3) += eps;
    H.col(k) = Eigen::Map<Eigen::VectorXd>(fp.data(), 3 * n) - Eigen::Map<Eigen::VectorXd>(fm.data(), 3 * n);
    H.col(k) /= 2 * eps;
  }
  return 0.5 * (H + H.transpose());
}

// The dense KKT step [M̃ −Jᵀ; J α̃][Δx; Δλ] = −[g; h] over the free dofs, M̃ = M + `stiffness` (free
// block), g kept or zero. Returns Δx (3 × n, 0 at pins) and Δλ.
void dense_kkt(const Case& c, const Eigen::MatrixXd& stiffness, bool keep, Eigen::Matrix3Xd& dx, Eigen::VectorXd& dl) {
  const int n = c.prob.particles.size(), m = c.prob.num_constraints();
  std::vector<int> dofs;
  for (int i = 0; i < n; ++i)
    if (c.prob.particles.w[i] > 0)
      for (int d = 0; d < 3; ++d) dofs.push_back(3 * i + d);
  const int nf = static_cast<int>(dofs.size());
  const Eigen::MatrixXd J = dense_J(c);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nf + m, nf + m);
  Eigen::VectorXd rhs(nf + m);
  DualSystem ds(c.prob);
  Eigen::Matrix3Xd g;
  primal_residual_vector(c.prob, ds, c.s, c.prob.particles.x, c.x_pred, c.lambda, g);
  for (int a = 0; a < nf; ++a) {
    K(a, a) = 1 / c.prob.particles.w[dofs[a] / 3];
    for (int b = 0; b < nf; ++b) K(a, b) += stiffness(dofs[a], dofs[b]);
    for (int j = 0; j < m; ++j) {
      K(a, nf + j) = -J(j, dofs[a]);
      K(nf + j, a) = J(j, dofs[a]);
    }
    rhs[a] = keep ? -g(dofs[a] % 3, dofs[a] / 3) : 0.0;
  }
  for (int j = 0; j < m; ++j) {
    K(nf + j, nf + j) = c.alpha_tilde[j];
    rhs[nf + j] = -(c.s.C[j] + c.alpha_tilde[j] * c.lambda[j]);
  }
  const Eigen::VectorXd sol = K.fullPivLu().solve(rhs);
  dx = Eigen::Matrix3Xd::Zero(3, n);
  for (int a = 0; a < nf; ++a) dx(dofs[a] % 3, dofs[a] / 3) = sol[a];
  dl = sol.tail(m);
}

// The harness's step on the case, by exact cholmod.
void harness_step(Case& c, const std::string& form, const std::string& stiffness, const std::string& keep,
                  Eigen::Matrix3Xd& dx, Eigen::VectorXd& dl) {
  set_param(c.p, "form", form, "test");
  set_param(c.p, "xpbd.geometric_stiffness", stiffness, "test");
  set_param(c.p, "xpbd.primal_residual", keep, "test");
  c.p.linear.tol = 1e-13;
  DualSystem ds(c.prob);
  GlobalStep step(c.prob, ds, "cholmod", c.p, c.alpha_tilde);
  Eigen::Matrix3Xd g;
  primal_residual_vector(c.prob, ds, c.s, c.prob.particles.x, c.x_pred, c.lambda, g);
  const Vector b = -(c.s.C + c.alpha_tilde.cwiseProduct(c.lambda));
  const GlobalStepInput in{c.s, c.lambda, c.prob.particles.x, g, b, Projection::clamp};
  step.prepare(in);
  const LinearStats st = step.solve(in, SetupKind::Structure, {}, dl, dx);
  ASSERT_NE(st.status, LinearStatus::breakdown) << st.message;
}

double rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }
}  // namespace

class KktStep : public ::testing::TestWithParam<std::string> {};

// keep (g on the right) with M̃ = M: both forms give the dense KKT step; zero does not.
TEST_P(KktStep, KeepMatchesTheDenseKktSolveInBothForms) {
  for (const std::string form : {"dual", "primal"}) {
    Case c = stretched_bar(GetParam());
    Eigen::Matrix3Xd dx, dx_ref;
    Eigen::VectorXd dl, dl_ref;
    const int n = c.prob.particles.size();
    dense_kkt(c, Eigen::MatrixXd::Zero(3 * n, 3 * n), true, dx_ref, dl_ref);
    harness_step(c, form, "none", "keep", dx, dl);
    EXPECT_LT(rel(dx, dx_ref), 1e-8) << form;
    EXPECT_LT(rel(dl, dl_ref), 1e-8) << form;
    harness_step(c, form, "none", "zero", dx, dl);  // the test can tell the two apart
    EXPECT_GT(rel(dx, dx_ref), 1e-3) << form;
  }
}

// full + keep (primal form): the dense KKT step with the exact top-left block M − Σλ_j∇²C_j.
TEST_P(KktStep, FullAndKeepMatchTheDenseKktSolveWithTheHessian) {
  Case c = stretched_bar(GetParam());
  const Eigen::MatrixXd H = lambda_hessian_fd(c);
  Eigen::Matrix3Xd dx, dx_ref, dx_none;
  Eigen::VectorXd dl, dl_ref;
  dense_kkt(c, -H, true, dx_ref, dl_ref);
  harness_step(c, "primal", "full", "keep", dx, dl);
  EXPECT_LT(rel(dx, dx_ref), 1e-5);
  EXPECT_LT(rel(dl, dl_ref), 1e-5);
  harness_step(c, "primal", "none", "keep", dx_none, dl);  // without the Hessian: another step
  EXPECT_GT(rel(dx_none, dx_ref), 1e2 * rel(dx, dx_ref));
}

// diagonal: the same Δλ and Δx in both forms, and the dense KKT step with M̃ = M + K̃_d.
TEST_P(KktStep, DiagonalGivesTheSameStepInBothForms) {
  for (const std::string keep : {"zero", "keep"}) {
    Case c = stretched_bar(GetParam());
    Eigen::Matrix3Xd dx_d, dx_p, dx_ref;
    Eigen::VectorXd dl_d, dl_p, dl_ref;
    harness_step(c, "dual", "diagonal", keep, dx_d, dl_d);
    harness_step(c, "primal", "diagonal", keep, dx_p, dl_p);
    EXPECT_LT(rel(dl_p, dl_d), 1e-8) << keep;
    EXPECT_LT(rel(dx_p, dx_d), 1e-8) << keep;
    // K̃_d: the diagonal of −Σλ_j∇²C_j's particle blocks (finite differences), kept ≥ 0.
    const Eigen::MatrixXd H = lambda_hessian_fd(c);
    const Eigen::VectorXd kd = (-H.diagonal()).cwiseMax(0.0);
    dense_kkt(c, Eigen::MatrixXd(kd.asDiagonal()), keep == "keep", dx_ref, dl_ref);
    EXPECT_LT(rel(dl_d, dl_ref), 1e-5) << keep;
    EXPECT_LT(rel(dx_d, dx_ref), 1e-5) << keep;
    EXPECT_GT(kd.maxCoeff(), 0.0);  // the case has geometric stiffness to add
  }
}
INSTANTIATE_TEST_SUITE_P(Scenes, KktStep, ::testing::Values("bar_hang", "cloth_hang"));

TEST(KktStep, FullRefusesTheDualForm) {
  Case c = stretched_bar("bar_hang");
  set_param(c.p, "form", "dual", "test");
  set_param(c.p, "xpbd.geometric_stiffness", "full", "test");
  DualSystem ds(c.prob);
  try {
    GlobalStep step(c.prob, ds, "cholmod", c.p, c.alpha_tilde);
    FAIL() << "full in the dual form was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("xpbd.geometric_stiffness=full"), std::string::npos) << e.what();
  }
}
