// The parts of the Newton loop, each where it can break: progressive's selective projection, the
// ρ-driven switch of rho_switch and the ρ it reads (the model actually solved), the ε-active set of
// contact, the rounding floor of ‖∇E‖ and the rounding of E against their measured noise, and the
// stop criterion's order.
#include "harness/sim/hessian_projection.hpp"
#include "harness/sim/newton.hpp"
#include "harness/sim/newton_loop.hpp"
#include "harness/sim/plane_bounds.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/residual_energy.hpp"
#include "problems/scene.hpp"
#include "harness/sim/sim_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace xb;
using xb::test::newton_params;

namespace {
// h²∇E at x per particle (0 at pins).
Eigen::Matrix3Xd gradient(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                          const Eigen::VectorXd& at) {
  ConstraintState s;
  evaluate_constraints(prob, x, s, newton_rest_epsilon);
  Eigen::VectorXd lambda;
  eliminate_multipliers(s, at, lambda);
  Eigen::Matrix3Xd g;
  primal_residual_vector(prob, DualSystem(prob), s, x, x_pred, lambda, g);
  return g;
}

Eigen::Matrix3Xd predicted_start(const Problem& prob, double h) {
  Eigen::Matrix3Xd x = prob.particles.x;
  for (int i = 0; i < prob.particles.size(); ++i)
    if (prob.particles.w[i] > 0) x.col(i) += h * (prob.particles.v.col(i) + h * prob.gravity);
  return x;
}
}  // namespace

// With tolerance τ, exactly the elements whose smallest exact eigenvalue is below −τ of their own
// stiffness (ψ_j = λ_min α̃_j) enter clamped; every other one, indefinite or not, enters exact. On
// a twisted bar with its nodes shaken (tets flat, inverted and stretched: ψ across the range).
TEST(ProjectionStrategy, ProgressiveProjectsOnlyTheElementsBelowMinusTau) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  Problem prob = build_problem(p);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) prob.particles.x(d, i) += 0.3 * p.size / p.resolution * u(rng);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt);
  const Eigen::Matrix3Xd& x = prob.particles.x;
  ElementHessians exact(prob), clamped(prob), progressive(prob);
  exact.fill_energy_hessian(x, at, ElementProjection{Projection::none, 0});
  clamped.fill_energy_hessian(x, at, ElementProjection{Projection::clamp, 0});
  for (const double tau : {0.1, 1.0}) {
    progressive.fill_energy_hessian(x, at, ElementProjection{Projection::clamp, tau});
    int below = 0, kept_indefinite = 0;
    for (int j = 0; j < prob.num_constraints(); ++j) {
      const double psi = exact.smallest_eigenvalues()[j] * at[j];
      const auto& want = psi < -tau ? clamped.blocks().matrix(j) : exact.blocks().matrix(j);
      const double scale = exact.blocks().matrix(j).norm();
      EXPECT_LE((progressive.blocks().matrix(j) - want).norm(), 1e-12 * scale) << "tau " << tau << ", element " << j;
      below += psi < -tau;
      kept_indefinite += psi < 0 && psi >= -tau;
    }
    EXPECT_GT(below, 0) << tau;
    EXPECT_GT(kept_indefinite, 0) << tau;
    EXPECT_EQ(progressive.projected_elements(), below) << tau;
  }
}

// rho_switch: clamp while the last step's decrease was ≥ 1/4 of the model's, abs after one that was
// not (or after a model that predicted no decrease), clamp again after a good one.
TEST(ProjectionStrategy, RhoSwitchFollowsRho) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  const Problem prob = build_problem(p);
  ProjectionStrategy s(prob, parse_projection_strategy("rho_switch"), 1e-2);
  s.begin_substep();
  EXPECT_EQ(s.first(0, 1).base, Projection::clamp);
  s.after_step(0.2, 1.0);
  EXPECT_EQ(s.first(1, 1).base, Projection::abs);
  s.after_step(0.3, 1.0);
  EXPECT_EQ(s.first(2, 1).base, Projection::clamp);
  s.after_step(1.0, -1.0);
  EXPECT_EQ(s.first(3, 1).base, Projection::abs);
  s.begin_substep();
  EXPECT_EQ(s.first(0, 1).base, Projection::clamp);
  EXPECT_THROW(parse_projection_strategy("trust_region"), std::exception);
}

namespace {
// A deliberately inexact linear solve: 0.6 K⁻¹b + 0.05 b‖K⁻¹b‖/‖b‖ (a descent direction, not a
// Galerkin one: ΔxᵀKΔx ≠ −∇E·Δx, unlike any CG iterate started at zero).
class InexactSolve : public LinearSolver {
 public:
  InexactSolve() : LinearSolver(1e-12) {}
  std::string name() const override { return "test-inexact"; }
  void setup(const SparseMatrix& A, SetupKind, const SetupContext&) override { ldlt_.compute(Eigen::MatrixXd(A)); }
  LinearStats solve(const Vector& b, Vector& x) override {
    const Vector exact = ldlt_.solve(b);
    x = 0.6 * exact + 0.05 * exact.norm() / b.norm() * b;
    LinearStats st;
    st.iterations = 1;
    st.residual_history = {b.norm()};
    st.residual_time = {0};
    return st;
  }

 private:
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};
}  // namespace

// The ρ the strategies read is the model the step solved: its predicted decrease is
// −(∇E·s + ½sᵀ∇²E s) at the step s taken, whatever the linear solve left (here a deliberately
// inexact one), checked against sᵀ∇²E s by central differences of ∇E along s. The exact solve's
// identity ΔxᵀKΔx = −∇E·Δx, which the old prediction assumed, is off by 1000 times more here.
TEST(NewtonLoop, RhoReadsTheModelActuallySolved) {
  if (!find_method("test-inexact"))
    register_method({"test-inexact", false, true, "", "an inexact solve (tests)"},
                    [](const SolverSettings&) { return std::make_unique<InexactSolve>(); });
  Params p = newton_params("mass_chain");
  p.resolution = 16;
  p.hessian_projection = "clamp";  // a hanging chain's Hessian at x̃ is PSD: clamped = exact
  p.linear.stop_norm = "primal";   // one solve, no refinement rounds that would make it exact
  const Problem prob = build_problem(p);
  const double h = p.dt / p.substeps, h2 = h * h;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  const Eigen::Matrix3Xd x_pred = predicted_start(prob, h);
  DualSystem ds(prob);
  GlobalStep step(prob, ds, "test-inexact", p, at);
  NewtonLoop loop(prob, ds, step, at, h, NewtonSettings::from(p));
  std::vector<Eigen::Matrix3Xd> xs;
  std::vector<StepRecord> recs;
  NewtonHooks hooks;
  hooks.on_iterate = [&](const NewtonIterate& v) {
    xs.push_back(v.x);
    recs.push_back(v.last);
  };
  Eigen::Matrix3Xd x;
  loop.minimise(x, x_pred, hooks);
  ASSERT_GE(xs.size(), 2u);
  const Eigen::Matrix3Xd s = xs[1] - xs[0];
  const Eigen::Matrix3Xd g = gradient(prob, xs[0], x_pred, at);
  const double d = 1e-4;  // central differences of h²∇E along s
  const Eigen::Matrix3Xd Hs = (gradient(prob, xs[0] + d * s, x_pred, at) - gradient(prob, xs[0] - d * s, x_pred, at)) / (2 * d);
  const double slope = particle_dot(prob, g, s), curvature = particle_dot(prob, s, Hs);
  const double model = -(slope + 0.5 * curvature) / h2;
  EXPECT_NEAR(recs[1].predicted, model, 1e-5 * std::abs(model));
  EXPECT_GT(recs[1].predicted, 0);
  const double t = recs[1].length, assumed = -slope * (1 - t / 2) / h2;  // ΔxᵀKΔx = −∇E·Δx, Δx = s/t
  EXPECT_GT(std::abs(assumed - model), 0.05 * std::abs(model)) << "the solve was not inexact enough to tell";
}

// Contact's ε-active set (Bertsekas): ε_k = ‖x − P(x − M⁻¹g)‖_∞; a particle within ε of the plane
// that E pushes down is held, one farther up or one pulled up is not; ε = 0 at a solution.
TEST(PlaneBounds, TheStepHoldsTheEpsilonActiveSet) {
  Problem prob;
  prob.particles.x = Eigen::Matrix3Xd::Zero(3, 4);
  prob.particles.x.row(1) << 0, 1e-6, 1, 0;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 4);
  prob.particles.w = Eigen::Vector4d(0.5, 0.5, 0.5, 0.5);
  prob.planes.push_back(PlaneCollider{0.0});
  const PlaneBounds b(prob);
  Eigen::Matrix3Xd g = Eigen::Matrix3Xd::Zero(3, 4);
  g.row(1) << 1.0, 1e-5, 1e-5, -1e-7;  // on the plane pushed; just above pushed; far above; on it pulled
  std::vector<int> active;
  b.active_set(prob.particles.x, g, active);
  EXPECT_EQ(active, std::vector<int>({0}));
  const double eps = b.epsilon(prob.particles.x, g);
  EXPECT_NEAR(eps, 5e-6, 1e-15);  // far above: w·g_y
  b.active_set(prob.particles.x, g, active, eps);
  EXPECT_EQ(active, std::vector<int>({0, 1}));
  Eigen::Matrix3Xd solved = Eigen::Matrix3Xd::Zero(3, 4);
  solved(1, 0) = 1.0;
  EXPECT_EQ(b.epsilon(prob.particles.x, solved), 0.0);
}

namespace {
// The largest change of h²∇E (in its 2-norm over free particles) under 8 random perturbations of
// each coordinate by ±ε of its size: the noise the rounding of x's inputs puts into ∇E.
double gradient_noise(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                      const Eigen::VectorXd& at) {
  std::mt19937 rng(3);
  std::bernoulli_distribution sign;
  const Eigen::Matrix3Xd g0 = gradient(prob, x, x_pred, at);
  double noise = 0;
  for (int k = 0; k < 8; ++k) {
    Eigen::Matrix3Xd y = x;
    for (long i = 0; i < y.size(); ++i) y.data()[i] *= 1 + (sign(rng) ? 1 : -1) * std::numeric_limits<double>::epsilon();
    const Eigen::Matrix3Xd d = gradient(prob, y, x_pred, at) - g0;
    noise = std::max(noise, std::sqrt(particle_dot(prob, d, d)));
  }
  return noise;
}
}  // namespace

// The rounding floor of ‖∇E‖ (newton.hpp) against the noise measured at x̃ and at the reference: at
// least a third of it (below that the stop test would stop on noise) and at most 30 times it (a
// floor 1000 times too large, which would end solves early as "rounding_floor", fails here).
TEST(Rounding, TheGradientFloorBoundsItsNoiseFromBothSides) {
  for (const std::string scene : {"cloth_hang", "twist_bar", "mass_chain"}) {
    Params p = newton_params(scene);
    if (scene != "mass_chain") p.resolution = scene == "twist_bar" ? 2 : 8;
    const Problem prob = build_problem(p);
    const double h = p.dt / p.substeps;
    const Eigen::VectorXd at = scaled_compliance(prob, h);
    const Eigen::Matrix3Xd x_pred = predicted_start(prob, h);
    ReferenceSolver ref(prob, p, at);
    const Eigen::Matrix3Xd x_ref = ref.solve(x_pred).x;
    for (const Eigen::Matrix3Xd* x : {&x_pred, &x_ref}) {
      ConstraintState s;
      evaluate_constraints(prob, *x, s, newton_rest_epsilon);
      const double floor = gradient_rounding_floor(prob, DualSystem(prob), s, *x, at);
      const double noise = gradient_noise(prob, *x, x_pred, at);
      EXPECT_GE(floor, noise / 3) << scene << (x == &x_ref ? " at the reference" : " at x~");
      EXPECT_LE(floor, 30 * noise) << scene << (x == &x_ref ? " at the reference" : " at x~");
    }
  }
}

// E's rounding (newton.hpp: energy_rounding, what the line search's trapezoid test engages at)
// against the spread of the computed E under translations of the scene by its own size (E is
// translation invariant; the rounding of its terms is not): between a third and 30 times it.
TEST(Rounding, TheEnergyRoundingMatchesTheNoiseOfE) {
  for (const std::string scene : {"cloth_hang", "twist_bar", "mass_chain"}) {
    Params p = newton_params(scene);
    if (scene != "mass_chain") p.resolution = scene == "twist_bar" ? 2 : 8;
    const Problem prob = build_problem(p);
    const double h = p.dt / p.substeps;
    const Eigen::VectorXd at = scaled_compliance(prob, h);
    const Eigen::Matrix3Xd x_pred = predicted_start(prob, h);
    const Eigen::Matrix3Xd x = ReferenceSolver(prob, p, at).solve(x_pred).x;
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    const double size = x.cwiseAbs().maxCoeff();
    double spread = 0, rounding = 0, e0 = 0;
    for (int k = 0; k < 12; ++k) {
      const Eigen::Vector3d T = k == 0 ? Eigen::Vector3d::Zero().eval() : Eigen::Vector3d(Eigen::Vector3d(u(rng), u(rng), u(rng)) * size);
      const Eigen::Matrix3Xd y = x.colwise() + T, y_pred = x_pred.colwise() + T;
      ConstraintState s;
      evaluate_constraints(prob, y, s, newton_rest_epsilon);
      const double e = incremental_energy(prob, s, y, y_pred, h);
      if (k == 0) e0 = e;
      spread = std::max(spread, std::abs(e - e0));
      rounding = std::max(rounding, energy_rounding(prob, s, y, y_pred, h, e));
    }
    EXPECT_GE(rounding, spread / 3) << scene;
    EXPECT_LE(rounding, 30 * spread) << scene;
  }
}

// The stop criterion's order: not finite, diverged, converged, at the floor, the iteration limit;
// a failed line search near the floor is its own reason, and no success.
TEST(StopCriterion, OrderAndTheFailedSearchNearTheFloor) {
  StopCriterion c;
  c.rtol = 1e-8;
  c.atol = 1e-9;
  c.max_iterations = 10;
  EXPECT_EQ(c.test(0, 1.0, 1.0, 0.0), StopReason::running);
  EXPECT_EQ(c.test(1, NAN, 1.0, 0.0), StopReason::not_finite);
  EXPECT_EQ(c.test(1, 1.0, 1.0, 0.0, false), StopReason::not_finite);
  EXPECT_EQ(c.test(1, 2e8, 1.0, 0.0), StopReason::diverged);
  EXPECT_EQ(c.test(10, 1e-9, 1.0, 1e-3), StopReason::converged);
  EXPECT_EQ(c.test(10, 1e-3, 1.0, 1e-3), StopReason::rounding_floor);
  EXPECT_EQ(c.test(10, 1e-2, 1.0, 1e-3), StopReason::max_iterations);
  EXPECT_EQ(StopCriterion::failed_search(0.05, 1e-3), StopReason::line_search_at_floor);
  EXPECT_EQ(StopCriterion::failed_search(0.5, 1e-3), StopReason::line_search_failed);
  EXPECT_FALSE(stop_reason_success(StopReason::line_search_at_floor));
  EXPECT_TRUE(stop_reason_success(StopReason::rounding_floor));
  EXPECT_EQ(stop_reason_name(StopReason::line_search_at_floor), "line_search_at_floor");
  // A collapsed trust region by the same floor rule, under its own names; every name reads back.
  EXPECT_EQ(StopCriterion::failed_region(0.05, 1e-3), StopReason::trust_region_at_floor);
  EXPECT_EQ(StopCriterion::failed_region(0.5, 1e-3), StopReason::trust_region_failed);
  EXPECT_FALSE(stop_reason_success(StopReason::trust_region_at_floor));
  for (int i = 0; i <= static_cast<int>(StopReason::interrupted); ++i)
    EXPECT_EQ(static_cast<int>(stop_reason_from_name(stop_reason_name(static_cast<StopReason>(i)))), i);
}
