// The stepper and the baseline methods on cases with known answers.
#include "harness/sim/simulation.hpp"
#include "core/error.hpp"
#include "problems/dual_system.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>

using namespace xb;

namespace {
// One particle of mass m hanging from a pin by a spring of rest length l0 and compliance α.
// From rest, the implicit step minimises ‖x − x̃‖²_M/(2h²) + C²/(2α): the extension is
// s = d·m/(m + h²/α), d = h²·g the predicted drop.
Problem pendulum(double m, double alpha) {
  Problem p;
  p.name = "pendulum";
  p.particles.x.resize(3, 2);
  p.particles.x << 0, 0, 0, -1, 0, 0;  // pin at the origin, particle at y = −1
  p.particles.v = Eigen::Matrix3Xd::Zero(3, 2);
  p.particles.w = Eigen::Vector2d(0, 1 / m);
  p.distance.idx = {{0, 1}};
  p.distance.rest_length = {1.0};
  p.distance.compliance = {alpha};
  p.gravity = Eigen::Vector3d(0, -9.8, 0);
  return p;
}
}  // namespace

class Pendulum : public ::testing::TestWithParam<std::string> {};

TEST_P(Pendulum, ConvergesToTheAnalyticImplicitStep) {
  const double m = 2.0, alpha = 1e-4, h = 1e-2;
  Params p;
  p.dt = h;
  p.max_iterations = 200;
  p.rtol = 0;
  p.atol = 1e-14;
  const RunResult r = run_simulation(pendulum(m, alpha), p, GetParam());
  ASSERT_EQ(r.status, "ok") << r.message;
  const double d = h * h * 9.8;
  const double s = d * m / (m + h * h / alpha);
  EXPECT_NEAR(-r.final_positions(1, 1), 1.0 + s, 1e-12);
  EXPECT_EQ(r.final_positions(1, 0), 0.0);  // the pin did not move
}
INSTANTIATE_TEST_SUITE_P(Methods, Pendulum, ::testing::Values("cholmod", "cg", "jacobi-pcg", "xpbd-gs", "xpbd-jacobi"));

// Gauss–Seidel over colours gives the same bits for every thread count.
TEST(XpbdGs, DeterministicAcrossThreadCounts) {
  Params p;
  p.scene = "bar_hang";
  p.resolution = 3;
  p.prestretch = 1.05;
  p.stiffness = 1e9;
  p.max_iterations = 20;
  const Problem prob = build_problem(p);
  p.threads = 1;
  const RunResult a = run_simulation(prob, p, "xpbd-gs");
  p.threads = 2;
  const RunResult b = run_simulation(prob, p, "xpbd-gs");
  ASSERT_EQ(a.final_positions.size(), b.final_positions.size());
  EXPECT_EQ((a.final_positions - b.final_positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(a.log.dual_residual, b.log.dual_residual);
}

// The linear baselines against a dense solve of a real dual system.
TEST(LinearSolvers, MatchDenseSolveOnBarSystem) {
  Params p;
  p.scene = "bar_hang";
  p.resolution = 3;
  p.aspect = 2;
  p.linear.tol = 1e-12;
  p.linear.max_iterations = 5000;
  Problem prob = build_problem(p);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  for (int i = 0; i < prob.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) prob.particles.x(d, i) += u(rng);
  DualSystem ds(prob);
  ConstraintState s;
  evaluate_constraints(prob, prob.particles.x, s);
  ds.fill(s, scaled_compliance(prob, p.dt));
  const Eigen::VectorXd b = -s.C;
  const Eigen::VectorXd ref = Eigen::MatrixXd(ds.A()).ldlt().solve(b);
  for (const char* name : {"cholmod", "cg", "jacobi-pcg"}) {
    auto solver = make_linear_solver(name, p);
    solver->setup(ds.A(), SetupKind::Structure, {});
    Eigen::VectorXd x;
    const LinearStats st = solver->solve(b, x);
    EXPECT_EQ(st.status, LinearStatus::converged) << name;
    EXPECT_LE((x - ref).norm(), 1e-8 * ref.norm()) << name;
    EXPECT_LE(st.final_relative_residual, 1e-11) << name;
    EXPECT_EQ(st.residual_history.size(), st.residual_time.size()) << name;
    // A values-only setup after a change of values is still exact.
    Eigen::VectorXd at = scaled_compliance(prob, p.dt) * 3.0;
    ds.fill(s, at);
    solver->setup(ds.A(), SetupKind::Values, {});
    solver->solve(b, x);
    const Eigen::VectorXd ref2 = Eigen::MatrixXd(ds.A()).ldlt().solve(b);
    EXPECT_LE((x - ref2).norm(), 1e-8 * ref2.norm()) << name;
    ds.fill(s, scaled_compliance(prob, p.dt));
  }
}

// CHOLMOD reports a singular system (compliance 0, a constraint with no free particle... here:
// two identical constraints, a redundant pair) as breakdown, not a crash.
TEST(LinearSolvers, CholmodReportsSingularAsBreakdown) {
  Problem prob = pendulum(1.0, 0.0);
  prob.distance.idx.push_back({0, 1});
  prob.distance.rest_length.push_back(1.0);
  prob.distance.compliance.push_back(0.0);
  Params p;
  p.dt = 1e-2;
  const RunResult r = run_simulation(prob, p, "cholmod");
  EXPECT_EQ(r.status, "breakdown");
  EXPECT_NE(r.message.find("positive definite"), std::string::npos) << r.message;
}

// Out of memory in a run is its status `out_of_memory` saying so and in which step, never a
// std::bad_alloc. In a child process whose address space is capped a little above what it has
// mapped, one thread (no OpenMP thread to start), the run's first large allocations fail.
TEST(Simulation, OutOfMemoryIsAnErrorSayingWhere) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves the address space this caps, and aborts where malloc would fail";
#endif
  Params p;
  p.scene = "cloth_hang";
  p.resolution = 160;
  p.threads = 1;
  p.max_iterations = 2;
  const Problem prob = build_problem(p);
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    long pages = 0;
    std::ifstream("/proc/self/statm") >> pages;
    const rlim_t mapped = static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE));
    const rlimit cap{mapped + (rlim_t{24} << 20), mapped + (rlim_t{24} << 20)};
    if (::setrlimit(RLIMIT_AS, &cap) != 0) ::_exit(3);
    const RunResult r = run_simulation(prob, p, "mgpbd");
    std::fprintf(stderr, "status %s: %s\n", r.status.c_str(), r.message.c_str());
    ::_exit(r.status == "out_of_memory" && r.message.rfind("out of memory in ", 0) == 0 ? 0 : 1);
  }
  int st = 0;
  ASSERT_EQ(::waitpid(pid, &st, 0), pid);
  ASSERT_TRUE(WIFEXITED(st)) << "the child crashed (signal " << (WIFSIGNALED(st) ? WTERMSIG(st) : 0) << ")";
  EXPECT_EQ(WEXITSTATUS(st), 0) << "see the child's status line above";
}

// step = newton without the constraints' Hessians (xpbd.geometric_stiffness none or diagonal) would
// be Gauss–Newton on E recorded as Newton (exact_hessian 1 included): refused, naming the key.
TEST(Simulation, NewtonWithoutTheConstraintHessiansIsRefused) {
  Params p;
  load_scene_file(std::string(XB_SOURCE_DIR) + "/problems/scenes/bar_hang.toml", p);
  p.resolution = 2;
  p.step = "newton";
  p.form = "primal";
  p.primal_residual = "keep";
  for (const std::string gs : {"none", "diagonal"}) {
    p.geometric_stiffness = gs;
    try {
      run_simulation(build_problem(p), p, "cholmod");
      ADD_FAILURE() << "step=newton ran with xpbd.geometric_stiffness=" << gs;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("step=newton needs xpbd.geometric_stiffness=full"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("Gauss-Newton"), std::string::npos) << e.what();
    }
  }
  p.geometric_stiffness = "full";
  p.max_iterations = 2;
  EXPECT_NE(run_simulation(build_problem(p), p, "cholmod").status, "error");
}
