// CHOLMOD with cholmod.refactor = lagged: an older matrix's factor preconditions CG on the current
// one. Checked against the exact (dense) solve of the current matrix in both forms, with the
// actions and counts that show the old factor was really used, and the refactorisation rules.
#include "core/error.hpp"
#include "core/process_memory.hpp"
#include "harness/params.hpp"
#include "harness/sim/primal_solve.hpp"
#include "problems/dual_system.hpp"
#include "problems/primal_system.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <SuiteSparse_config.h>
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdlib>
#include <random>
#include <set>

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

namespace {
// Dense PCG from zero on A preconditioned by the solve of M: the residual norms of its first n
// iterations.
std::vector<double> dense_pcg_residuals(const Eigen::MatrixXd& A, const Eigen::LDLT<Eigen::MatrixXd>& M,
                                        const Vector& b, int n) {
  Vector r = b, z = M.solve(r), p = z;
  double rz = r.dot(z);
  std::vector<double> h{r.norm()};
  for (int k = 0; k < n; ++k) {
    const Vector Ap = A * p;
    const double a = rz / p.dot(Ap);
    r -= a * Ap;
    h.push_back(r.norm());
    z = M.solve(r);
    const double rz1 = r.dot(z);
    p = z + (rz1 / rz) * p;
    rz = rz1;
  }
  return h;
}
}  // namespace

// With an iteration bound the old factor cannot meet, the solve factorises the current matrix and
// goes on from where the old factor's CG stopped: its history is that CG's (dense PCG here) and
// then the new factor's, in units of ‖b‖ throughout; x = x_old + A⁻¹(b − A x_old) is the exact
// solution (a dropped x_old or an unscaled correction would not be).
TEST(CholmodLagged, FactorisesInsideTheSolvePastTheBound) {
  const int bound = 2;
  Params p = bar_params(1e-11);
  p.cholmod.lagged_max_iterations = bound;
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
  EXPECT_EQ(st.iterations, bound + 1) << "the new (exact) factor finishes in one iteration";
  const std::vector<double> old_cg =
      dense_pcg_residuals(Eigen::MatrixXd(d2.A()), Eigen::MatrixXd(d1.A()).ldlt(), b, bound);
  ASSERT_GT(old_cg[bound], 1e-11 * b.norm()) << "the old factor must miss the tolerance in `bound` iterations";
  for (int k = 0; k <= bound; ++k) EXPECT_NEAR(st.residual_history[k], old_cg[k], 1e-8 * old_cg[0]) << k;
  EXPECT_LE(st.residual_history.back(), 1e-11 * b.norm());
  for (size_t k = 1; k < st.residual_time.size(); ++k) EXPECT_GE(st.residual_time[k], st.residual_time[k - 1]) << k;
}

// Primal form: the lagged factor of K judged on the dual residual gives the exact Δλ to the
// asked tolerance.
TEST(CholmodLagged, PrimalSolveWithAnOldFactorMeetsTheDualTolerance) {
  for (double tol : {1e-3, 1e-8}) {
    Params p = bar_params(tol);
    p.cholmod.lagged_max_iterations = 1000;  // the old factor all the way (the default 30 refactorised at 1e-8)
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
    // The old factor solved it: no factorisation inside the solve, one in all.
    EXPECT_EQ(primal.solver().statistics().at("refactorisations_in_solve"), 0) << tol;
    EXPECT_EQ(primal.solver().statistics().at("factorisations"), 1) << tol;
    EXPECT_EQ(primal.solver().last_setup_action(), "lagged") << tol;
  }
}

// Out of memory reads as such, with the step and the factor's size, not as a status code. Every
// SuiteSparse allocation of half the factor's values or more fails here: the analysis (arrays of
// the matrix's size) passes, the factorisation (the factor's values) does not.
namespace {
size_t g_largest_allowed = 0;
void* bounded_malloc(size_t n) { return n > g_largest_allowed ? nullptr : std::malloc(n); }
void* bounded_calloc(size_t n, size_t m) { return n * m > g_largest_allowed ? nullptr : std::calloc(n, m); }
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
  auto sized = make_linear_solver("cholmod", p);  // the factor's size, with every allocation allowed
  sized->setup(ds.A(), SetupKind::Structure, {});
  const double factor_nnz = sized->statistics().at("factor_nnz");
  g_largest_allowed = static_cast<size_t>(factor_nnz * sizeof(double) / 2);
  auto solver = make_linear_solver("cholmod", p);
  void* (*saved)(size_t) = SuiteSparse_config.malloc_func;
  void* (*saved_calloc)(size_t, size_t) = SuiteSparse_config.calloc_func;
  SuiteSparse_config.malloc_func = bounded_malloc;
  SuiteSparse_config.calloc_func = bounded_calloc;
  std::string said;
  try {
    solver->setup(ds.A(), SetupKind::Structure, {});
  } catch (const OutOfMemory& e) {  // a std::bad_alloc: the run's status out_of_memory
    said = e.what();
  }
  SuiteSparse_config.malloc_func = saved;
  SuiteSparse_config.calloc_func = saved_calloc;
  EXPECT_NE(said.find("out of memory in CHOLMOD's factorisation: the factor needs " +
                      std::to_string(static_cast<long long>(factor_nnz)) + " non-zeros"),
            std::string::npos)
      << said;
}

// Under a memory limit (RLIMIT_DATA, as `run --memory-limit` sets it) that the factor's non-zeros
// from the symbolic analysis would pass, the setup ends before the numeric factorisation, saying
// so; with room for it, it factorises. The limit is the process's: set, then restored.
TEST(Cholmod, FactorOverTheMemoryLimitIsRefusedBeforeFactorising) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's shadow memory is in the data segment this limits";
#endif
  Params p;
  p.scene = "cloth_hang";
  p.resolution = 64;
  const Problem prob = build_problem(p);
  DualSystem ds(prob);
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  ds.fill(s, scaled_compliance(prob, p.dt));
  auto sized = make_linear_solver("cholmod", p);
  sized->setup(ds.A(), SetupKind::Structure, {});
  const double factor_bytes = sized->statistics().at("factor_nnz") * (sizeof(double) + sizeof(int));
  rlimit saved{};
  ASSERT_EQ(getrlimit(RLIMIT_DATA, &saved), 0);
  for (const bool room : {false, true}) {  // half the factor's bytes above the data segment, or all and 512 MB
    auto solver = make_linear_solver("cholmod", p);
    set_data_limit(data_bytes() + static_cast<long long>(room ? factor_bytes + 512e6 : factor_bytes / 2));
    std::string said;
    try {
      solver->setup(ds.A(), SetupKind::Structure, {});
    } catch (const OutOfMemory& e) {
      said = e.what();
    }
    ASSERT_EQ(setrlimit(RLIMIT_DATA, &saved), 0);
    if (room) {
      EXPECT_EQ(said, "");
      EXPECT_EQ(solver->statistics().at("factorisations"), 1);
    } else {
      EXPECT_NE(said.find("CHOLMOD's factor would not fit the memory limit"), std::string::npos) << said;
      EXPECT_EQ(solver->statistics().at("factorisations"), 0);  // refused before factorising
    }
  }
}

// A CHOLMOD solve or factorisation that runs out of memory inside the lagged CG (every SuiteSparse
// allocation after the first k fails, for each k until none does) ends the solve with
// xb::OutOfMemory saying which (the run's status out_of_memory), never with a crash or a read of the
// failed solve's empty result; a solve that completes is right. The energy stop norm takes the
// branch that applies the new factor to b and r after a refactorisation.
namespace {
long g_allocations_left = -1;  // -1: no limit
bool allocation_allowed() {
  if (g_allocations_left == 0) return false;
  if (g_allocations_left > 0) --g_allocations_left;
  return true;
}
void* counted_malloc(size_t n) { return allocation_allowed() ? std::malloc(n) : nullptr; }
void* counted_calloc(size_t n, size_t m) { return allocation_allowed() ? std::calloc(n, m) : nullptr; }
}  // namespace

TEST(CholmodLagged, FailedAllocationsInTheSolveAreOutOfMemory) {
  Params p = bar_params(1e-11);
  p.cholmod.lagged_max_iterations = 1;
  set_param(p, "linear.stop_norm", "energy", "test");
  const Problem prob = build_problem(p);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt);
  const State s1 = perturbed(prob, p, 0.01, 3), s2 = perturbed(prob, p, 0.2, 4);
  DualSystem d1(prob), d2(prob);
  d1.fill(s1.s, at);
  d2.fill(s2.s, at);
  const Vector b = -s2.s.C;
  const Vector ref = Eigen::MatrixXd(d2.A()).ldlt().solve(b);
  void* (*saved)(size_t) = SuiteSparse_config.malloc_func;
  void* (*saved_calloc)(size_t, size_t) = SuiteSparse_config.calloc_func;
  std::set<std::string> said;
  bool completed = false;
  for (long k = 0; k < 1000 && !completed; ++k) {
    auto solver = make_linear_solver("cholmod", p);
    solver->setup(d1.A(), SetupKind::Structure, {});
    solver->setup(d2.A(), SetupKind::Values, {});
    Vector x;
    LinearStats st;
    g_allocations_left = k;
    SuiteSparse_config.malloc_func = counted_malloc;
    SuiteSparse_config.calloc_func = counted_calloc;
    bool oom = false;
    try {
      st = solver->solve(b, x);
    } catch (const OutOfMemory& e) {
      oom = true;
      said.insert(std::string(e.what()).substr(0, 40));
    }
    SuiteSparse_config.malloc_func = saved;
    SuiteSparse_config.calloc_func = saved_calloc;
    completed = g_allocations_left > 0;  // no allocation was refused
    g_allocations_left = -1;
    if (!oom) {
      EXPECT_NE(st.status, LinearStatus::breakdown) << k << ": " << st.message;
      EXPECT_LE((x - ref).norm(), 1e-7 * ref.norm()) << k;
    }
  }
  EXPECT_TRUE(completed);
  // The old factor's solve and the refactorisation both ran out.
  EXPECT_EQ(said, (std::set<std::string>{"out of memory in CHOLMOD's factorisation", "out of memory in CHOLMOD's solve with a "}));
}
