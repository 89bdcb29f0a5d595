// The one Newton loop (harness/sim/newton_loop.hpp): the descent safeguard against an exact solve
// of an indefinite Hessian, the reference against an independent dense Newton, contact's optimality
// conditions, and the stop reasons the runs record.
#include "harness/cli/profile.hpp"
#include "harness/sim/newton.hpp"
#include "problems/constraint_hessian.hpp"
#include "harness/sim/newton_loop.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/residual_energy.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"
#include "harness/sim/sim_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace xb;
using xb::test::newton_params;

namespace {
// Eigen's dense LDLᵀ as a LinearSolver: the exact step on any symmetric K, indefinite included
// (where CHOLMOD's Cholesky breaks down).
class DenseLdlt : public LinearSolver {
 public:
  DenseLdlt() : LinearSolver(1e-12) {}
  std::string name() const override { return "test-dense-ldlt"; }
  void setup(const SparseMatrix& A, SetupKind, const SetupContext&) override { ldlt_.compute(Eigen::MatrixXd(A)); }
  LinearStats solve(const Vector& b, Vector& x) override {
    x = ldlt_.solve(b);
    LinearStats st;
    st.iterations = 1;
    st.residual_history = {b.norm()};
    st.residual_time = {0};
    return st;
  }

 private:
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

struct DenseLdltRegistration {
  DenseLdltRegistration() {
    if (!find_method("test-dense-ldlt"))
      register_method({"test-dense-ldlt", false, true, "", "dense LDL^T (tests)"},
                      [](const SolverSettings&) { return std::make_unique<DenseLdlt>(); });
  }
};

// h²∇E at x, all particles' dofs (0 at pins).
Eigen::VectorXd gradient(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                         const Eigen::VectorXd& at) {
  ConstraintState s;
  evaluate_constraints(prob, x, s, newton_rest_epsilon);
  Eigen::VectorXd lambda;
  eliminate_multipliers(s, at, lambda);
  Eigen::Matrix3Xd g;
  primal_residual_vector(prob, DualSystem(prob), s, x, x_pred, lambda, g);
  return Eigen::Map<Eigen::VectorXd>(g.data(), g.size());
}
}  // namespace

// Two springs (rest length 1, 1/α̃ = 2, unit masses) from a pin, both compressed, at x̃ = their
// start: the exact Hessian is indefinite (eigenvalues −1.2 and −0.2 among six) and its Newton step,
// solved exactly by a dense LDLᵀ, climbs E (∇E·Δx = +0.18‖∇E‖²·…, checked below). The safeguard
// solves again clamped, which descends; without it the line search gets an ascent direction and
// the substep fails.
TEST(NewtonLoop, DescentSafeguardReplacesAnAscentStep) {
  const DenseLdltRegistration reg;
  const double h = 1e-2;
  Problem prob;
  prob.name = "springs";
  prob.particles.x.resize(3, 3);
  prob.particles.x << 0, 0.2, -0.1, 0, -0.1, -0.7, 0, 0.6, 0.9;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 3);
  prob.particles.w = Eigen::Vector3d(0, 1, 1);
  prob.distance.idx = {{0, 1}, {1, 2}};
  prob.distance.rest_length = {1.0, 1.0};
  prob.distance.compliance = {0.5 * h * h, 0.5 * h * h};  // 1/α̃ = 2
  Params p = newton_params("mass_chain");
  p.dt = h;
  p.substeps = 1;
  p.hessian_projection = "on_demand";
  p.rtol = 1e-12;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  const Eigen::Matrix3Xd x_pred = prob.particles.x;
  {  // the exact Newton step at x̃ climbs E
    Eigen::MatrixXd K = Eigen::MatrixXd::Identity(9, 9);
    for (int j = 0; j < 2; ++j) {
      const auto& e = prob.distance.idx[j];
      const Matrix6d H = distance_energy_hessian(x_pred.col(e[0]), x_pred.col(e[1]), 1.0, at[j], Projection::none);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) K.block<3, 3>(3 * e[a], 3 * e[b]) += H.block<3, 3>(3 * a, 3 * b);
    }
    const Eigen::MatrixXd Kf = K.bottomRightCorner<6, 6>();
    const Eigen::VectorXd g = gradient(prob, x_pred, x_pred, at).tail<6>();
    ASSERT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Kf).eigenvalues()[0], -1);
    ASSERT_GT(g.dot(-Kf.ldlt().solve(g)), 0.1 * g.squaredNorm());
  }
  DualSystem ds(prob);
  GlobalStep step(prob, ds, "test-dense-ldlt", p, at);
  NewtonLoop loop(prob, ds, step, at, h, NewtonSettings::from(p));
  Eigen::Matrix3Xd x;
  std::vector<StepRecord> steps;
  std::vector<double> energy;
  NewtonHooks hooks;
  hooks.on_iterate = [&](const NewtonIterate& v) {
    if (v.iteration > 0) steps.push_back(v.last);
    energy.push_back(v.energy);
  };
  const NewtonOutcome o = loop.minimise(x, x_pred, hooks);
  EXPECT_TRUE(stop_reason_success(o.reason)) << stop_reason_name(o.reason);
  ASSERT_GE(steps.size(), 1u);
  EXPECT_EQ(steps[0].solves, 2);  // the exact try, then the clamped one
  EXPECT_FALSE(steps[0].exact);
  EXPECT_LT(energy[1], energy[0]);
}

// The reference (the stepper's Newton loop, CHOLMOD, sparse element Hessians) against a dense Newton
// written here from h²∇E alone: its Hessian by central differences, Eigen's LDLᵀ, halving on E.
TEST(NewtonLoop, ReferenceMatchesAnIndependentDenseNewton) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  p.aspect = 2;
  const Problem prob = build_problem(p);
  const double h = p.dt / p.substeps;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  const Eigen::Matrix3Xd x_pred = prob.particles.x + h * prob.particles.v;
  ReferenceSolver ref(prob, p, at);
  const ReferenceSolution rs = ref.solve(x_pred);
  ASSERT_EQ(rs.status, StopReason::converged);
  // The dense Newton on the free dofs.
  std::vector<int> dofs;
  for (int k = 0; k < 3 * prob.particles.size(); ++k)
    if (prob.particles.w[k / 3] > 0) dofs.push_back(k);
  const int n = static_cast<int>(dofs.size());
  Eigen::Matrix3Xd x = x_pred;
  auto energy = [&](const Eigen::Matrix3Xd& y) {
    ConstraintState s;
    evaluate_constraints(prob, y, s, newton_rest_epsilon);
    return incremental_energy(prob, s, y, x_pred, h);
  };
  const double g0 = gradient(prob, x, x_pred, at).norm();
  for (int it = 0; it < 30 && gradient(prob, x, x_pred, at).norm() > 1e-11 * g0; ++it) {
    const Eigen::VectorXd g = gradient(prob, x, x_pred, at);
    Eigen::MatrixXd H(n, n);
    const double eps = 1e-6 * p.size;
    for (int b = 0; b < n; ++b) {
      Eigen::Matrix3Xd xp = x, xm = x;
      xp(dofs[b] % 3, dofs[b] / 3) += eps;
      xm(dofs[b] % 3, dofs[b] / 3) -= eps;
      const Eigen::VectorXd d = (gradient(prob, xp, x_pred, at) - gradient(prob, xm, x_pred, at)) / (2 * eps);
      for (int a = 0; a < n; ++a) H(a, b) = d[dofs[a]];
    }
    H = 0.5 * (H + H.transpose()).eval();
    Eigen::VectorXd gf(n);
    for (int a = 0; a < n; ++a) gf[a] = g[dofs[a]];
    const Eigen::VectorXd d = H.ldlt().solve(-gf);
    Eigen::Matrix3Xd dx = Eigen::Matrix3Xd::Zero(3, prob.particles.size());
    for (int a = 0; a < n; ++a) dx(dofs[a] % 3, dofs[a] / 3) = d[a];
    double t = 1;
    while (t > 1e-6 && energy(x + t * dx) > energy(x)) t /= 2;
    x += t * dx;
  }
  ASSERT_LE(gradient(prob, x, x_pred, at).norm(), 1e-9 * g0);
  EXPECT_LE(mass_norm_distance(prob, x, rs.x), 1e-7 * mass_norm_distance(prob, rs.x, x_pred));
}

// ball_drop's reference with the ball predicted 1 cm through the plane: the minimiser of E over
// y ≥ 0 meets the contact's optimality conditions — no particle below the plane, on the plane no
// pulling force (h²∂E/∂y ≥ 0: E would fall going down, the plane pushes), every other gradient
// component zero — and some particles do touch with a pushing force.
TEST(NewtonLoop, ContactReferenceMeetsTheOptimalityConditions) {
  Params p = newton_params("ball_drop");
  p.resolution = 4;
  const Problem prob = build_problem(p);
  ASSERT_EQ(prob.planes.size(), 1u);
  const double h = p.dt / p.substeps;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  Eigen::Matrix3Xd x_pred = prob.particles.x;
  x_pred.row(1).array() -= x_pred.row(1).minCoeff() + 0.01;
  ReferenceSolver ref(prob, p, at);
  const ReferenceSolution rs = ref.solve(x_pred);
  ASSERT_TRUE(stop_reason_success(rs.status)) << stop_reason_name(rs.status);
  Eigen::Matrix3Xd start = x_pred;
  start.row(1) = start.row(1).cwiseMax(0.0);
  const Eigen::VectorXd g0 = gradient(prob, start, x_pred, at);
  const Eigen::VectorXd g = gradient(prob, rs.x, x_pred, at);
  const double tol = 1e-8 * g0.norm();
  int touching = 0, pushing = 0;
  double free_sq = 0;
  for (int i = 0; i < prob.particles.size(); ++i) {
    if (!(prob.particles.w[i] > 0)) continue;
    EXPECT_GE(rs.x(1, i), 0.0) << "particle " << i << " below the plane";
    const bool on_plane = rs.x(1, i) <= 0;
    for (int d = 0; d < 3; ++d) {
      const double gd = g[3 * i + d];
      if (on_plane && d == 1) {
        EXPECT_GE(gd, -tol) << "particle " << i << " pulled by the plane";
        ++touching;
        if (gd > 1e3 * tol) ++pushing;
      } else {
        free_sq += gd * gd;
      }
    }
  }
  EXPECT_LE(std::sqrt(free_sq), tol);
  EXPECT_GT(touching, 0);
  EXPECT_GT(pushing, 0);
}

// A run to the rounding floor: with rtol = atol = 0 only the floor can end a substep, and that is
// a success (status ok, substep_status rounding_floor, substep_success 1), not a failed line search.
// On the mass chain's second substep plain Armijo blocks before it, within 1e2 of it: that is
// line_search_at_floor, its own reason and no success (the run's status line_search_failed says so).
TEST(NewtonLoop, TheRoundingFloorIsSuccessAndAFailedSearchNearItIsNot) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  p.stiffness = 7e9;
  p.rtol = 0;
  p.atol = 0;
  p.max_iterations = 40;
  const RunResult r = run_simulation(build_problem(p), p, "cholmod");
  ASSERT_EQ(r.status, "ok") << r.message;
  ASSERT_EQ(r.log.substep_status.size(), 1u);
  EXPECT_EQ(r.log.substep_status[0], "rounding_floor");
  EXPECT_EQ(r.log.substep_success[0], 1);
  EXPECT_LT(r.log.iteration.back(), 40);
  EXPECT_LE(r.log.relative_newton_residual.back(), r.log.relative_gradient_floor.back());
  EXPECT_EQ(r.stats.at("substeps_rounding_floor"), 1);
  Params c = newton_params("mass_chain");
  c.frames = 2;
  c.rtol = 0;
  c.atol = 0;
  c.max_iterations = 60;
  c.line_search = "armijo";
  const RunResult a = run_simulation(build_problem(c), c, "cholmod");
  ASSERT_EQ(a.log.substep_status.size(), 2u);
  EXPECT_EQ(a.log.substep_status[1], "line_search_at_floor");
  EXPECT_EQ(a.log.substep_success[1], 0);
  EXPECT_GT(a.log.relative_newton_residual.back(), a.log.relative_gradient_floor.back());
  EXPECT_LE(a.log.relative_newton_residual.back(), 1e2 * a.log.relative_gradient_floor.back());
  EXPECT_EQ(a.status, "line_search_failed");
  EXPECT_NE(a.message.find("line_search_at_floor"), std::string::npos) << a.message;
}

// Every projection strategy converges on the small squash (the default ball), E never rising by
// more than its rounding, and the reference's status is read into the run's. Each strategy is
// itself: every one but clamp takes another path than clamp's (a strategy that fell back to the
// clamp everywhere fails here; rho_switch is the clamp wherever every step's ρ ≥ 1/4, as here:
// tests/harness/sim/test_newton_parts.cpp tests its switch), and the exact strategies leave some
// step exact.
TEST(NewtonLoop, EveryStrategyConvergesOnTheSquash) {
  std::vector<double> clamp_energy;
  for (const std::string& strategy : hessian_projection_choices()) {
    Params p = newton_params("squash");
    p.hessian_projection = strategy;
    p.max_iterations = 60;
    RunOptions opt;
    opt.reference = true;
    const RunResult r = run_simulation(build_problem(p), p, "cholmod", opt);
    EXPECT_EQ(r.status, "ok") << strategy << ": " << r.message;
    for (size_t k = 0; k + 1 < r.log.energy.size(); ++k)
      EXPECT_LE(r.log.energy[k + 1], r.log.energy[k] * (1 + 1e-12)) << strategy << " " << k;
    ASSERT_EQ(r.log.reference_status.size(), 1u);
    EXPECT_EQ(r.log.reference_success[0], 1);
    EXPECT_EQ(r.log.reference_certified[0], 1) << r.log.reference_certificate_note[0];
    EXPECT_LT(r.log.position_error.back(), 1e-4) << strategy;
    if (strategy == "clamp" || strategy == "rho_switch") {
      if (strategy == "clamp") clamp_energy = r.log.energy;
      continue;
    }
    ASSERT_FALSE(clamp_energy.empty()) << "clamp is the first choice";
    bool differs = r.log.energy.size() != clamp_energy.size();
    for (size_t k = 0; !differs && k < clamp_energy.size(); ++k)
      differs = std::abs(r.log.energy[k] - clamp_energy[k]) > 1e-12 * std::abs(clamp_energy[k]);
    EXPECT_TRUE(differs) << strategy << " took the clamp's path";
    if (strategy == "adaptive" || strategy == "on_demand" || strategy == "progressive") {
      long long exact = 0;
      for (long long e : r.log.exact_hessian) exact += e;
      EXPECT_GT(exact, 0) << strategy;
    }
  }
}

// A reference that does not converge is the run's status, not only an attribute: XPBD's fixed point
// as the reference of a stiff twisted bar stagnates far from E's minimiser; the Newton run itself
// converges, and its status says the reference did not.
TEST(NewtonLoop, AnUnconvergedReferenceIsTheRunsStatus) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  p.stiffness = 7e9;
  p.reference_method = "xpbd";
  RunOptions opt;
  opt.reference = true;
  const RunResult r = run_simulation(build_problem(p), p, "cholmod", opt);
  ASSERT_EQ(r.log.substep_status.size(), 1u);
  EXPECT_EQ(r.log.substep_status[0], "converged");
  EXPECT_EQ(r.status, "reference_unconverged");
  EXPECT_NE(r.message.find("the reference did not converge in 1 of 1 substeps"), std::string::npos) << r.message;
  EXPECT_NE(r.log.reference_status[0], "converged");
  EXPECT_EQ(r.log.reference_success[0], 0);
  EXPECT_EQ(r.log.reference_certified[0], 0);  // an XPBD fixed point has no certificate
  ASSERT_EQ(r.log.reference_time.size(), 1u);
  EXPECT_GT(r.log.reference_time[0], 0);
  EXPECT_LE(r.log.reference_time[0], r.reference_time);
}

// progressive's τ (docs/newton.md): 1 at a substep's start, a decade up after each step the model
// predicted well (up to 1e3: every element exact), unchanged after a poor one; a failed try is
// retried at 0.1, and one at 0.1 with every element clamped; the next substep starts again at 1.
TEST(ProjectionStrategy, ProgressiveTauFollowsTheModelAndTheFailures) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  const Problem prob = build_problem(p);
  ProjectionStrategy s(prob, ProjectionStrategyKind::progressive, 1e-2);
  s.begin_substep();
  auto tau = [&](int it) { return s.first(it, 1).tolerance; };
  EXPECT_EQ(tau(0), 1);
  EXPECT_EQ(s.first(0, 1).base, Projection::clamp);
  s.after_step(1.0, 1.0);
  EXPECT_EQ(tau(1), 10);
  s.after_step(0.5, 1.0);  // a poor step leaves τ
  EXPECT_EQ(tau(2), 10);
  ElementProjection more, last;
  ASSERT_TRUE(s.next(s.first(3, 1), more));  // τ = 10 failed: the retry at 0.1
  EXPECT_EQ(more.base, Projection::clamp);
  EXPECT_EQ(more.tolerance, 0.1);
  ASSERT_TRUE(s.next(more, last));  // 0.1 failed too: every element clamped
  EXPECT_EQ(last.tolerance, 0);
  EXPECT_FALSE(s.next(last, more));  // the clamp failed: nothing left
  s.after_step(1.0, 1.0);
  EXPECT_EQ(tau(4), 0.1);
  for (int k = 0; k < 5; ++k) s.after_step(1.0, 1.0);
  EXPECT_EQ(tau(5), 1e3);
  EXPECT_EQ(s.first(5, 1).base, Projection::none);  // exact everywhere
  s.begin_substep();
  EXPECT_EQ(tau(0), 1);
}
