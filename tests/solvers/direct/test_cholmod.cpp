// CHOLMOD with cholmod.refactor = lagged: an older matrix's factor preconditions CG on the current
// one. Checked against the exact (dense) solve of the current matrix in both forms, with the
// actions and counts that show the old factor was really used, and the refactorisation rules.
#include "harness/params.hpp"
#include "harness/sim/primal_solve.hpp"
#include "problems/dual_system.hpp"
#include "problems/primal_system.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <SuiteSparse_config.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

using namespace xb;

namespace {

// A bar whose particles are moved at random by `amount` of a cell, its constraints evaluated.
struct State {
  ConstraintState s;
  Eigen::Matrix3Xd x;
};
State perturbed(const Problem& prob, const Params& p, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  State st{{}, prob.particles.x};
  for (int i = 0; i < st.x.cols(); ++i)
    for (int d = 0; d < 3; ++d) st.x(d, i) += amount * p.size / p.resolution * u(rng);
  evaluate_constraints(prob, st.x, st.s);
  return st;
}

Params bar_params(double tol) {
  Params p;
  p.scene = "bar_hang";
  p.resolution = 3;
  p.aspect = 2;
  p.linear.tol = tol;
  p.cholmod.refactor = "lagged";
  return p;
}

}  // namespace

// Dual form: the second matrix of a frame is solved with the first one's factor, to the asked
// tolerance, and equals the exact solution to that accuracy; a new frame factorises again.
TEST(CholmodLagged, DualSolveWithAnOldFactorMeetsTheTolerance) {
  for (double tol : {1e-3, 1e-11}) {
    Params p = bar_params(tol);
    p.cholmod.lagged_max_iterations = 1000;  // never refactorised inside the solve here
    const Problem prob = build_problem(p);
    const Eigen::VectorXd at = scaled_compliance(prob, p.dt);
    const State s1 = perturbed(prob, p, 0.01, 3), s2 = perturbed(prob, p, 0.05, 4);
    DualSystem d1(prob), d2(prob);
    d1.fill(s1.s, at);
    d2.fill(s2.s, at);
    auto solver = make_linear_solver("cholmod", p);
    solver->setup(d1.A(), SetupKind::Structure, SetupContext{0, 0, 0});
    EXPECT_EQ(solver->last_setup_action(), "analyse+factorise");
    Vector x;
    solver->solve(-s1.s.C, x);
    solver->setup(d2.A(), SetupKind::Values, SetupContext{0, 0, 1});
    EXPECT_EQ(solver->last_setup_action(), "lagged");
    const Vector b = -s2.s.C;
    const LinearStats st = solver->solve(b, x);
    EXPECT_EQ(st.status, LinearStatus::converged);
    EXPECT_GT(st.iterations, 1) << "a fresh factor would solve in one iteration";
    const Vector ref = Eigen::MatrixXd(d2.A()).ldlt().solve(b);
    const double rel = (b - d2.A() * x).norm() / b.norm();
    EXPECT_LE(rel, tol);
    EXPECT_NEAR(st.final_relative_residual, rel, 1e-3 * tol);
    if (tol < 1e-8) {
      EXPECT_LE((x - ref).norm(), 1e-7 * ref.norm());
    }
    EXPECT_EQ(solver->statistics().at("factorisations"), 1);
    EXPECT_EQ(solver->statistics().at("lagged_setups"), 1);
    // The first setup of the next frame factorises again.
    solver->setup(d2.A(), SetupKind::Values, SetupContext{1, 0, 0});
    EXPECT_EQ(solver->last_setup_action(), "factorise");
    EXPECT_EQ(solver->solve(b, x).iterations, 1);
  }
}

// With an iteration bound the old factor cannot meet, the solve factorises the current matrix and
// finishes with it.
TEST(CholmodLagged, FactorisesInsideTheSolvePastTheBound) {
  Params p = bar_params(1e-11);
  p.cholmod.lagged_max_iterations = 1;
  const Problem prob = build_problem(p);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt);
  const State s1 = perturbed(prob, p, 0.01, 3), s2 = perturbed(prob, p, 0.2, 4);
  DualSystem d1(prob), d2(prob);
  d1.fill(s1.s, at);
  d2.fill(s2.s, at);
  auto solver = make_linear_solver("cholmod", p);
  solver->setup(d1.A(), SetupKind::Structure, {});
  solver->setup(d2.A(), SetupKind::Values, {});
  const Vector b = -s2.s.C;
  Vector x;
  const LinearStats st = solver->solve(b, x);
  EXPECT_EQ(st.status, LinearStatus::converged);
  EXPECT_EQ(solver->last_setup_action(), "lagged+factorise");
  EXPECT_EQ(solver->statistics().at("refactorisations_in_solve"), 1);
  EXPECT_EQ(solver->statistics().at("factorisations"), 2);
  const Vector ref = Eigen::MatrixXd(d2.A()).ldlt().solve(b);
  EXPECT_LE((x - ref).norm(), 1e-7 * ref.norm());
  EXPECT_EQ(st.residual_history.size(), st.residual_time.size());
  EXPECT_EQ(static_cast<int>(st.residual_history.size()), st.iterations + 1);
}

// Primal form: the lagged factor of K judged on the dual residual gives the exact Δλ to the
// asked tolerance.
TEST(CholmodLagged, PrimalSolveWithAnOldFactorMeetsTheDualTolerance) {
  for (double tol : {1e-3, 1e-8}) {
    const Params p = bar_params(tol);
    const Problem prob = build_problem(p);
    const Eigen::VectorXd at = scaled_compliance(prob, p.dt);
    const State s1 = perturbed(prob, p, 0.01, 3), s2 = perturbed(prob, p, 0.05, 4);
    PrimalSolve primal(make_linear_solver("cholmod", p), constraint_graph(prob), p.linear);
    Vector dl;
    primal.setup(s1.s.grad, at, s1.x, SetupKind::Structure, SetupContext{0, 0, 0});
    primal.solve(-s1.s.C, dl);
    primal.setup(s2.s.grad, at, s2.x, SetupKind::Values, SetupContext{0, 0, 1});
    EXPECT_EQ(primal.solver().last_setup_action(), "lagged");
    const Vector b = -s2.s.C;
    const LinearStats st = primal.solve(b, dl);
    EXPECT_EQ(st.status, LinearStatus::converged);
    EXPECT_GT(st.iterations, 1);
    DualSystem d2(prob);
    d2.fill(s2.s, at);
    const Vector ref = Eigen::MatrixXd(d2.A()).ldlt().solve(b);
    const double rel = (b - d2.A() * dl).norm() / b.norm();
    EXPECT_LE(rel, 1.01 * tol);
    if (tol < 1e-6) {
      EXPECT_LE((dl - ref).norm(), 1e-5 * ref.norm());
    }
  }
}

// Out of memory reads as such, with the step and the factor's size, not as a status code. Every
// SuiteSparse allocation above 256 KB fails here (the cloth's factor is larger).
namespace {
void* small_malloc_only(size_t n) { return n > (size_t{1} << 18) ? nullptr : std::malloc(n); }
}  // namespace

TEST(Cholmod, OutOfMemorySaysSoWithTheFactorsSize) {
  Params p;
  p.scene = "cloth_hang";
  p.resolution = 48;
  const Problem prob = build_problem(p);
  DualSystem ds(prob);
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  ds.fill(s, scaled_compliance(prob, p.dt));
  auto solver = make_linear_solver("cholmod", p);
  void* (*saved)(size_t) = SuiteSparse_config.malloc_func;
  SuiteSparse_config.malloc_func = small_malloc_only;
  solver->setup(ds.A(), SetupKind::Structure, {});
  SuiteSparse_config.malloc_func = saved;
  Vector x;
  const LinearStats st = solver->solve(-s.C, x);
  EXPECT_EQ(st.status, LinearStatus::breakdown);
  EXPECT_NE(st.message.find("out of memory in CHOLMOD's"), std::string::npos) << st.message;
}
