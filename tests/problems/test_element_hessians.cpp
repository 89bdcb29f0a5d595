// The second-order blocks of whole scenes in the two forms: K with the geometric stiffness
// (diagonal and full) against dense assemblies, the Newton matrix M + Σ H_j against finite
// differences of Δt²∇E, Δt²∇E against differences of E, and the diagonal's Δλ equal in both forms
// (dense solves; the recovery Δλ = α̃⁻¹(b − JΔx) is unchanged with M̃ in place of M).
#include "harness/cli/run_setup.hpp"
#include "harness/sim/residual_energy.hpp"
#include "problems/dual_system.hpp"
#include "problems/element_hessians.hpp"
#include "problems/primal_system.hpp"
#include "problems/scene.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <random>

using namespace xb;

namespace {

struct Case {
  Problem prob;
  ConstraintState s;
  Eigen::VectorXd alpha_tilde, lambda;
  double dt = 0;
};

// A small scene, positions perturbed, constraints evaluated, λ random of both signs.
Case make_case(const std::string& scene, const std::vector<std::string>& sets) {
  const Params p = resolve_params(scene, sets);
  Case c{build_problem(p), {}, {}, {}, p.dt};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const double scale = 0.05 * p.size / p.resolution;
  for (int i = 0; i < c.prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) c.prob.particles.x(d, i) += scale * u(rng);
  evaluate_constraints(c.prob, c.prob.particles.x, c.s);
  c.alpha_tilde = scaled_compliance(c.prob, p.dt);
  c.lambda = Eigen::VectorXd::NullaryExpr(c.prob.num_constraints(), [&] { return 1e3 * u(rng); });
  return c;
}

std::vector<Case> cases() {
  std::vector<Case> v;
  v.push_back(make_case("cantilever", {"resolution=2", "aspect=2", "stiffness=1e5"}));  // tets, pins
  v.push_back(make_case("heavy_rope", {"resolution=6"}));                               // distances, a pin
  return v;
}

// Dense index of each free particle's first dof, −1 if pinned.
std::vector<int> dof_of(const PrimalSystem& ps, int n) {
  std::vector<int> d(n, -1);
  for (size_t b = 0; b < ps.free_particles().size(); ++b) d[ps.free_particles()[b]] = 3 * static_cast<int>(b);
  return d;
}

// M + Σ_j blocks_j (+ Jᵀα̃⁻¹J), assembled densely and independently of PrimalSystem.
Eigen::MatrixXd dense_K(const Case& c, const PrimalSystem& ps, const ElementMatrices* blocks, bool gauss_newton) {
  const auto dof = dof_of(ps, c.prob.particles.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(ps.rows(), ps.rows());
  for (int p = 0; p < c.prob.particles.size(); ++p)
    if (dof[p] >= 0) K.block<3, 3>(dof[p], dof[p]).diagonal().setConstant(1 / c.prob.particles.w[p]);
  for (int j = 0; j < c.prob.num_constraints(); ++j) {
    const auto pj = c.prob.constraint_particles(j);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        if (pj[a] < 0 || pj[b] < 0 || dof[pj[a]] < 0 || dof[pj[b]] < 0) continue;
        auto blk = K.block<3, 3>(dof[pj[a]], dof[pj[b]]);
        if (blocks) blk += blocks->matrix(j).block<3, 3>(3 * a, 3 * b);
        if (gauss_newton) blk += c.s.grad[j][a] * c.s.grad[j][b].transpose() / c.alpha_tilde[j];
      }
  }
  return K;
}

// J over the free dofs, dense.
Eigen::MatrixXd dense_J(const Case& c, const PrimalSystem& ps) {
  const auto dof = dof_of(ps, c.prob.particles.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(c.prob.num_constraints(), ps.rows());
  for (int j = 0; j < c.prob.num_constraints(); ++j) {
    const auto pj = c.prob.constraint_particles(j);
    for (int a = 0; a < 4; ++a)
      if (pj[a] >= 0 && dof[pj[a]] >= 0) J.block<1, 3>(j, dof[pj[a]]) = c.s.grad[j][a].transpose();
  }
  return J;
}

// One thread for these tiny systems (OpenMP barriers spin badly on a loaded machine), restored after.
struct OneThread {
  int saved = omp_get_max_threads();
  OneThread() { omp_set_num_threads(1); }
  ~OneThread() { omp_set_num_threads(saved); }
};

double rel(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) { return (A - B).cwiseAbs().maxCoeff() / B.cwiseAbs().maxCoeff(); }

}  // namespace

TEST(ElementHessians, FullGeometricStiffnessInK) {
  const OneThread one;
  for (Case& c : cases())
    for (Projection proj : {Projection::none, Projection::clamp, Projection::abs}) {
      PrimalSystem ps(constraint_graph(c.prob));
      ElementHessians eh(c.prob);
      eh.fill_geometric_stiffness(c.prob.particles.x, c.lambda, proj);
      // The blocks are the single-constraint formulas.
      const int nd = static_cast<int>(c.prob.distance.size());
      const auto& x = c.prob.particles.x;
      if (nd < c.prob.num_constraints()) {  // the first tet
        const auto e = c.prob.constraint_particles(nd);
        EXPECT_EQ(Matrix12d(eh.blocks().matrix(nd)), tet_geometric_stiffness(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]),
                                                           c.prob.tets.Dm_inv[0], c.lambda[nd], proj));
      } else {  // the first distance
        const auto e = c.prob.constraint_particles(0);
        const Matrix6d D = eh.blocks().matrix(0);
        EXPECT_EQ(D, distance_geometric_stiffness(x.col(e[0]), x.col(e[1]), c.lambda[0], proj));
      }
      ps.fill_with_blocks(c.s.grad, c.alpha_tilde, eh.blocks());
      const Eigen::MatrixXd K(ps.K());
      EXPECT_LE(rel(K, dense_K(c, ps, &eh.blocks(), true)), 1e-13) << c.prob.name;
      EXPECT_EQ(K, K.transpose()) << c.prob.name;
      // Refilled without blocks, K is XPBD's again (no state left behind).
      ps.fill(c.s.grad, c.alpha_tilde);
      EXPECT_LE(rel(Eigen::MatrixXd(ps.K()), dense_K(c, ps, nullptr, true)), 1e-13);
    }
}

// The exact Newton matrix M + Σ H_j is the derivative of Δt²∇E = M(x − x̃) + Jᵀα̃⁻¹C, which is the
// derivative of Δt²E = Δt²·incremental_energy.
TEST(ElementHessians, NewtonMatrixAndGradientMatchFiniteDifferences) {
  const OneThread one;
  for (Case& c : cases()) {
    PrimalSystem ps(constraint_graph(c.prob));
    ElementHessians eh(c.prob);
    Eigen::Matrix3Xd x = c.prob.particles.x;
    const Eigen::Matrix3Xd x_pred = x + 0.01 * Eigen::Matrix3Xd::Random(3, x.cols());
    ConstraintState at_x, ref;
    eh.fill_energy_hessian(x, c.alpha_tilde, Projection::none, &at_x);
    evaluate_constraints(c.prob, x, ref);  // the state from the same pass is evaluate_constraints'
    EXPECT_EQ(at_x.C, ref.C);
    for (int j = 0; j < c.prob.num_constraints(); ++j)
      for (int a = 0; a < 4; ++a) EXPECT_EQ(at_x.grad[j][a], ref.grad[j][a]) << j << " " << a;
    ps.fill_energy_hessian(eh.blocks());
    const Eigen::MatrixXd K(ps.K());
    EXPECT_LE(rel(K, dense_K(c, ps, &eh.blocks(), false)), 1e-13);
    const auto& free = ps.free_particles();
    ConstraintState s;
    auto gradient = [&](const Eigen::Matrix3Xd& y) {
      evaluate_constraints(c.prob, y, s);
      Vector g;
      ps.energy_gradient(s.grad, s.C, c.alpha_tilde, y, x_pred, g);
      return g;
    };
    auto energy = [&](const Eigen::Matrix3Xd& y) {
      evaluate_constraints(c.prob, y, s);
      return c.dt * c.dt * incremental_energy(c.prob, s, y, x_pred, c.dt);
    };
    const Vector g0 = gradient(x);
    Eigen::MatrixXd fdK(ps.rows(), ps.rows());
    Vector fdg(ps.rows());
    const double h = 1e-7 * c.prob.particles.x.cwiseAbs().maxCoeff();
    for (int col = 0; col < ps.rows(); ++col) {
      Eigen::Matrix3Xd xp = x, xm = x;
      xp(col % 3, free[col / 3]) += h;
      xm(col % 3, free[col / 3]) -= h;
      fdK.col(col) = (gradient(xp) - gradient(xm)) / (2 * h);
      fdg[col] = (energy(xp) - energy(xm)) / (2 * h);
    }
    EXPECT_LE(rel(K, fdK), 1e-5) << c.prob.name;
    EXPECT_LE((g0 - fdg).cwiseAbs().maxCoeff(), 1e-5 * g0.cwiseAbs().maxCoeff()) << c.prob.name;
    // g at λ = −α̃⁻¹C is the same vector.
    evaluate_constraints(c.prob, x, s);
    Vector g;
    ps.primal_residual(s.grad, -s.C.cwiseQuotient(c.alpha_tilde), x, x_pred, g);
    EXPECT_LE((g - g0).cwiseAbs().maxCoeff(), 1e-14 * g0.cwiseAbs().maxCoeff());
  }
}

// §1.4's diagonal K̃_d: the clamped diagonal of Σ G_j; both forms give the same Δλ.
TEST(ElementHessians, DiagonalGivesTheSameStepInBothForms) {
  const OneThread one;
  for (Case& c : cases()) {
    PrimalSystem ps(constraint_graph(c.prob));
    ElementHessians eh(c.prob);
    Eigen::Matrix3Xd kd, w_dof;
    eh.geometric_stiffness_diagonal(c.prob.particles.x, c.lambda, kd);
    // Against the dense Σ G_j's diagonal, clamped (pinned particles 0).
    eh.fill_geometric_stiffness(c.prob.particles.x, c.lambda, Projection::none);
    const auto dof = dof_of(ps, c.prob.particles.size());
    const Eigen::MatrixXd G = dense_K(c, ps, &eh.blocks(), false);
    int clamped = 0;
    for (int p = 0; p < c.prob.particles.size(); ++p)
      for (int d = 0; d < 3; ++d) {
        const double ref = dof[p] < 0 ? 0.0 : std::max(0.0, G(dof[p] + d, dof[p] + d) - 1 / c.prob.particles.w[p]);
        EXPECT_NEAR(kd(d, p), ref, 1e-9 * G.diagonal().cwiseAbs().maxCoeff());
        clamped += dof[p] >= 0 && kd(d, p) == 0;
      }
    EXPECT_GT(clamped, 0) << c.prob.name << ": the case should exercise the clamp";
    EXPECT_GT(kd.maxCoeff(), 0) << c.prob.name;
    shifted_inverse_masses(c.prob.particles.w, kd, w_dof);
    // Dual: A = J M̃⁻¹ Jᵀ + α̃ (its fill against a dense product), solved densely.
    DualSystem ds(c.prob);
    ds.fill(c.s, c.alpha_tilde, w_dof);
    const Eigen::MatrixXd J = dense_J(c, ps);
    Eigen::VectorXd winv(ps.rows());
    for (size_t b = 0; b < ps.free_particles().size(); ++b) winv.segment<3>(3 * b) = w_dof.col(ps.free_particles()[b]);
    const Eigen::MatrixXd A = J * winv.asDiagonal() * J.transpose() + Eigen::MatrixXd(c.alpha_tilde.asDiagonal());
    EXPECT_LE(rel(Eigen::MatrixXd(ds.A()), A), 1e-13);
    const Vector b = -(c.s.C + c.alpha_tilde.cwiseProduct(c.lambda));
    const Vector dl_dual = A.ldlt().solve(b);
    // Primal: (M̃ + Jᵀα̃⁻¹J)Δx = Jᵀα̃⁻¹b, Δλ = α̃⁻¹(b − JΔx).
    ps.fill_with_diagonal(c.s.grad, c.alpha_tilde, kd);
    Vector f, dl_primal;
    ps.rhs(c.s.grad, c.alpha_tilde, b, f);
    const Vector dx = Eigen::MatrixXd(ps.K()).ldlt().solve(f);
    ps.recover(c.s.grad, c.alpha_tilde, b, dx, dl_primal);
    EXPECT_LE((dl_primal - dl_dual).norm(), 1e-8 * dl_dual.norm()) << c.prob.name;
    // Δx = M̃⁻¹JᵀΔλ from the dual side is the primal Δx.
    Eigen::Matrix3Xd dx_dual;
    ds.apply_minv_gradT(c.s, dl_dual, w_dof, dx_dual);
    for (size_t i = 0; i < ps.free_particles().size(); ++i)
      EXPECT_LE((dx_dual.col(ps.free_particles()[i]) - dx.segment<3>(3 * i)).norm(), 1e-8 * dx.norm());
    // An inexact Δx: the recovered Δλ's dual residual is −J M̃⁻¹ r_K.
    const Vector dx_bad = dx + 1e-3 * dx.norm() * Vector::Random(dx.size());
    const Vector r_K = f - Eigen::MatrixXd(ps.K()) * dx_bad;
    Vector dl_bad, r_dual;
    ps.recover(c.s.grad, c.alpha_tilde, b, dx_bad, dl_bad);
    ps.dual_residual(c.s.grad, r_K, w_dof, r_dual);
    EXPECT_LE((r_dual - (b - A * dl_bad)).norm(), 1e-8 * r_dual.norm());
  }
}

TEST(ElementHessians, EnergyHessianRefusesRigidConstraints) {
  Case c = make_case("heavy_rope", {"resolution=4"});
  c.alpha_tilde[1] = 0;
  ElementHessians eh(c.prob);
  EXPECT_THROW(eh.fill_energy_hessian(c.prob.particles.x, c.alpha_tilde, Projection::clamp), std::exception);
}

// lowest_mode: a tet's twist mode (the squash's flat start: σ₃ = 0, ψ = 1 − 2/σ₂ < 0) and a
// compressed distance's transverse direction are directions of the element's exact Hessian whose
// curvature δxᵀH_jδx is the element's smallest eigenvalue (ψ_min/α̃ for a tet), and a tet's mode
// moves no particle's centroid.
TEST(ElementHessians, LowestModeIsTheElementsNegativeCurvature) {
  for (const auto& [scene, sets] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"squash", {}}, {"heavy_rope", {"resolution=6"}}}) {
    Case c = make_case(scene, sets);
    if (scene == "heavy_rope") c.prob.particles.x *= 0.7;  // every link compressed
    const Eigen::Matrix3Xd& x = c.prob.particles.x;
    ElementHessians eh(c.prob);
    ConstraintState st;
    eh.evaluate(x, st);
    eh.fill_energy_hessian(x, c.alpha_tilde, ElementProjection{Projection::none, 0}, nullptr, true);
    int checked = 0;
    for (int j = 0; j < c.prob.num_constraints() && checked < 30; ++j) {
      if (!(eh.smallest_eigenvalues()[j] < 0)) continue;
      Eigen::Matrix<double, 12, 1> dx;
      const double curvature = eh.lowest_mode(x, c.alpha_tilde, j, dx);
      const int n = 3 * eh.blocks().slots(j);
      const Eigen::MatrixXd H = eh.blocks().matrix(j);
      const double exact = dx.head(n).dot(H * dx.head(n));
      EXPECT_NEAR(curvature, exact, 1e-9 * std::abs(exact)) << scene << " " << j;
      if (eh.blocks().slots(j) == 4) {
        EXPECT_NEAR(curvature, eh.smallest_eigenvalues()[j], 1e-9 * std::abs(curvature)) << scene << " " << j;
        const Eigen::Vector3d shift = dx.segment<3>(0) + dx.segment<3>(3) + dx.segment<3>(6) + dx.segment<3>(9);
        EXPECT_LT(shift.norm(), 1e-12 * dx.norm());
      } else {  // 4C/(lα̃) along [t, −t], twice the transverse eigenvalue of [B −B; −B B] per unit ‖t‖
        EXPECT_NEAR(curvature, 2 * eh.smallest_eigenvalues()[j] * dx.head(n).squaredNorm(), 1e-9 * std::abs(curvature));
      }
      ++checked;
    }
    EXPECT_GE(checked, 5) << scene;
  }
}
