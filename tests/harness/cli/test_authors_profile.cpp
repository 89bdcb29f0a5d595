// The authors' setup as options: their logged residual beside the true one, the
// line-search step, their XPBD baseline, the scene keys mesh_height / init, and --profile.
// Each test fails if its option is ignored: the numbers are analytic (a one-spring pendulum whose
// constraint stays linear along the motion) or compare the option on and off.
#include "harness/cli/report.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/io/run_record.hpp"
#include "harness/sim/line_search.hpp"
#include "harness/cli/profile.hpp"
#include "harness/io/state_io.hpp"
#include "harness/sim/simulation.hpp"
#include "core/error.hpp"
#include "problems/scene.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>

using namespace xb;

namespace {
// A particle of mass m hanging at y = −1 from a pin at the origin by a spring (rest length 1,
// compliance α). From rest the predictor drops it by d = h²g, so C(x̃) = d; every step moves it
// along the spring, where C is exactly linear: a step Δλ changes C by w·Δλ.
Problem pendulum(double m, double alpha, double gravity = -9.8) {
  Problem p;
  p.name = "pendulum";
  p.particles.x.resize(3, 2);
  p.particles.x << 0, 0, 0, -1, 0, 0;
  p.particles.v = Eigen::Matrix3Xd::Zero(3, 2);
  p.particles.w = Eigen::Vector2d(0, 1 / m);
  p.distance.idx = {{0, 1}};
  p.distance.rest_length = {1.0};
  p.distance.compliance = {alpha};
  p.gravity = Eigen::Vector3d(0, gravity, 0);
  return p;
}

struct Pendulum {
  double m = 2, alpha = 1e-4, h = 1e-2;
  double w() const { return 1 / m; }
  double at() const { return alpha / (h * h); }  // α̃
  double d() const { return h * h * 9.8; }        // C(x̃)
  Params params() const {
    Params p;
    p.dt = h;
    p.rtol = 0;
    p.atol = 0;
    return p;
  }
};

Params small_squash() {
  Params p = resolve_params("squash", {});
  p.resolution = 4;
  return p;
}
}  // namespace

// xpbd-authors: λ takes the full Δλ = −d/(w + α̃), x only 0.1·wΔλ. Its logged residual uses C(x̃);
// the true one the C of the moved particle.
TEST(AuthorsMetric, LocalMethodLogsCOfThePredictedState) {
  const Pendulum s;
  Params p = s.params();
  p.max_iterations = 1;
  const RunResult r = run_simulation(pendulum(s.m, s.alpha), p, "xpbd-authors");
  const double dl = -s.d() / (s.w() + s.at());
  const double authors = std::abs(s.d() + s.at() * dl);
  const double truth = std::abs(s.d() + 0.1 * s.w() * dl + s.at() * dl);
  ASSERT_EQ(r.log.authors_dual_residual.size(), 2u);
  EXPECT_NEAR(r.log.authors_dual_residual[0], s.d(), 1e-15);
  EXPECT_NEAR(r.log.dual_residual[0], s.d(), 1e-15);
  EXPECT_NEAR(r.log.authors_dual_residual[1], authors, 1e-12 * s.d());
  EXPECT_NEAR(r.log.dual_residual[1], truth, 1e-12 * s.d());
  EXPECT_NEAR(r.log.authors_relative_dual_residual[1], authors / s.d(), 1e-12);
}

// A global exact step (cholmod, ω = 1): the true residual is 0, the authors' ‖C(x₀) + α̃λ₁‖ is d·w/(w + α̃).
TEST(AuthorsMetric, GlobalMethodLogsCFromBeforeTheStep) {
  const Pendulum s;
  Params p = s.params();
  p.omega = 1;
  p.max_iterations = 1;
  const RunResult r = run_simulation(pendulum(s.m, s.alpha), p, "cholmod");
  ASSERT_EQ(r.log.authors_dual_residual.size(), 2u);
  EXPECT_NEAR(r.log.authors_dual_residual[1], s.d() * s.w() / (s.w() + s.at()), 1e-10 * s.d());
  EXPECT_LT(r.log.dual_residual[1], 1e-10 * s.d());
}

// residual_metric chooses what stops the loop: on the squash ball xpbd-authors' true residual
// falls below 0.8 of its start within a few sweeps, its logged one stays near 1.
TEST(AuthorsMetric, ResidualMetricChoosesTheStopTest) {
  Params p = small_squash();
  p.rtol = 0.8;
  p.max_iterations = 40;
  const Problem prob = build_problem(p);
  const RunResult truth = run_simulation(prob, p, "xpbd-authors");
  p.residual_metric = "authors";
  const RunResult authors = run_simulation(prob, p, "xpbd-authors");
  EXPECT_EQ(truth.status, "ok");
  EXPECT_LT(truth.outer_iterations, 40);
  EXPECT_EQ(authors.status, "max_iterations");
  EXPECT_EQ(authors.outer_iterations, 40);
  EXPECT_GT(authors.log.authors_relative_dual_residual.back(), 0.8);
}

// The backtracking on one linear constraint, λ already λ + Δλ: f(t) = |d + twΔλ + α̃Δλ|, against
// f(0) = |d + α̃Δλ|.
TEST(LineSearch, HalvesUntilTheDualResidualDecreases) {
  const Pendulum s;
  const Problem prob = pendulum(s.m, s.alpha);
  Eigen::Matrix3Xd x = prob.particles.x;
  x(1, 1) -= s.d();  // the predicted state: C = d
  const Eigen::VectorXd at = Eigen::VectorXd::Constant(1, s.at());
  ConstraintState scratch;
  Eigen::Matrix3Xd trial;
  auto search = [&](double dl) {
    const Eigen::VectorXd lambda = Eigen::VectorXd::Constant(1, dl);  // λ = 0 + Δλ
    Eigen::Matrix3Xd dx = Eigen::Matrix3Xd::Zero(3, 2);
    dx(1, 1) = -s.w() * dl;  // M⁻¹∇CᵀΔλ: ∇C of the particle is (0, −1, 0)
    return backtrack_dual_residual(prob, x, lambda, dx, at, std::abs(s.d() + s.at() * dl), scratch, trial);
  };
  // w = 1/2, α̃ = 1: x carries a = w/(w + α̃) = 1/3 of the exact step. With
  // Δλ = −1.4·d/(w + α̃): f(t)/d = |1/15 − 1.4t/3|; f(1) = 0.4, f(1/2) = 1/6, f(1/4) = 1/20 < 1/15.
  EXPECT_DOUBLE_EQ(s.w() / (s.w() + s.at()), 1.0 / 3);
  const LineSearchStep over = search(-1.4 * s.d() / (s.w() + s.at()));
  EXPECT_TRUE(over.decreased);
  EXPECT_EQ(over.t, 0.25);
  EXPECT_EQ(over.trials, 3);
  EXPECT_NEAR(over.residual, 0.05 * s.d(), 1e-9 * s.d());
  // The wrong sign: f(t)/d = 5/3 + t/3 > f(0)/d for every t > 0: halved 30 times, to 2⁻³⁰ < 1e-9,
  // then x stays.
  const LineSearchStep up = search(s.d() / (s.w() + s.at()));
  EXPECT_FALSE(up.decreased);
  EXPECT_EQ(up.t, 0.0);
  EXPECT_EQ(up.trials, 31);
}

// step = fixed takes ω (0.25: a quarter of the exact step each time, many iterations);
// line_search takes t = 1 and converges in one; step_length records either.
TEST(LineSearch, StepOptionReplacesOmegaAndIsRecorded) {
  const Pendulum s;
  Params p = s.params();
  p.omega = 0.25;
  p.rtol = 1e-10;
  p.max_iterations = 50;
  const RunResult fixed = run_simulation(pendulum(s.m, s.alpha), p, "cholmod");
  p.step = "line_search";
  const RunResult ls = run_simulation(pendulum(s.m, s.alpha), p, "cholmod");
  ASSERT_EQ(ls.status, "ok") << ls.message;
  EXPECT_EQ(ls.outer_iterations, 1);
  EXPECT_GT(fixed.outer_iterations, 10);
  ASSERT_EQ(ls.log.step_length.size(), 2u);
  EXPECT_EQ(ls.log.step_length[0], 0.0);
  EXPECT_EQ(ls.log.step_length[1], 1.0);
  for (size_t i = 1; i < fixed.log.step_length.size(); ++i) EXPECT_EQ(fixed.log.step_length[i], 0.25);
}

// xpbd-authors moves x by position_relaxation·wΔλ after one sweep; xpbd-jacobi is unchanged by the key.
TEST(XpbdAuthors, PositionRelaxationScalesOnlyTheMove) {
  const Pendulum s;
  Params p = s.params();
  p.max_iterations = 1;
  const double dl = -s.d() / (s.w() + s.at());
  for (double omega_x : {0.1, 0.5}) {
    p.xpbd.position_relaxation = omega_x;
    const RunResult r = run_simulation(pendulum(s.m, s.alpha), p, "xpbd-authors");
    // y = −1 − d at the prediction; the move along +y (shortening) is ω_x·w·|Δλ|.
    EXPECT_NEAR(r.final_positions(1, 1), -1 - s.d() - omega_x * s.w() * dl, 1e-14) << omega_x;
  }
  p.xpbd.position_relaxation = 0.5;
  const RunResult j1 = run_simulation(pendulum(s.m, s.alpha), p, "xpbd-jacobi");
  p.xpbd.position_relaxation = 0.1;
  const RunResult j2 = run_simulation(pendulum(s.m, s.alpha), p, "xpbd-jacobi");
  EXPECT_EQ(j1.final_positions, j2.final_positions);
}

// A compressed spring (C < 0 ≤ 1e-6) is skipped by xpbd-authors, corrected by xpbd-jacobi.
TEST(XpbdAuthors, SkipsConstraintsWithSmallC) {
  Problem prob = pendulum(1, 1e-6, 0.0);
  prob.particles.x(1, 1) = -0.999;  // 1 mm shorter than rest: C = −1e-3
  Params p;
  p.max_iterations = 1;
  p.rtol = p.atol = 0;
  const RunResult a = run_simulation(prob, p, "xpbd-authors");
  const RunResult j = run_simulation(prob, p, "xpbd-jacobi");
  EXPECT_EQ(a.final_positions(1, 1), -0.999);
  EXPECT_EQ(a.stats.at("authors_skipped_last_sweep"), 1.0);
  EXPECT_LT(j.final_positions(1, 1), -0.999 - 1e-5);
}

// mesh_height scales the rest mesh (volumes with it); init = enlarge starts squash at 1.5× about
// the centroid instead of collapsed.
TEST(SceneKeys, MeshHeightAndEnlarge) {
  Params p = small_squash();
  p.init = "enlarge";
  const Problem at_1m = build_problem(p);
  p.mesh_height = 0.2;
  const Problem at_02 = build_problem(p);
  auto y_extent = [](const Problem& q) { return q.particles.x.row(1).maxCoeff() - q.particles.x.row(1).minCoeff(); };
  EXPECT_NEAR(y_extent(at_02), 1.5 * 0.2, 1e-12);
  const double s = 0.2 / (y_extent(at_1m) / 1.5);
  const double v1 = std::accumulate(at_1m.tets.rest_volume.begin(), at_1m.tets.rest_volume.end(), 0.0);
  const double v2 = std::accumulate(at_02.tets.rest_volume.begin(), at_02.tets.rest_volume.end(), 0.0);
  EXPECT_NEAR(v2, v1 * s * s * s, 1e-12 * v1);
  p.mesh_height = 0;
  p.init = "none";
  const Problem squashed = build_problem(p);
  EXPECT_EQ(y_extent(squashed), 0.0);  // the default start: collapsed
  // enlarge is the rest mesh ×1.5 about its centroid (cantilever starts from the rest mesh).
  p.scene = "cantilever";
  const Eigen::Matrix3Xd rest = build_problem(p).particles.x;
  const Eigen::Vector3d c = rest.rowwise().mean();
  const Eigen::Matrix3Xd expected = ((rest.colwise() - c) * 1.5).colwise() + c;
  EXPECT_LT((at_1m.particles.x - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(SceneKeys, RefusedWhereTheyDoNotApply) {
  Params p;
  p.scene = "cloth_hang";
  p.mesh_height = 0.2;
  try {
    build_problem(p);
    FAIL() << "mesh_height accepted on cloth_hang";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mesh_height"), std::string::npos) << e.what();
  }
  Params q = small_squash();
  q.scene = "twist_bar";
  q.init = "enlarge";
  try {
    build_problem(q);
    FAIL() << "init accepted on twist_bar";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'init'"), std::string::npos) << e.what();
  }
}

// defaults < scene < profile < --set; [scenes.squash] only for squash.
TEST(Profile, AuthorsKeysAndPrecedence) {
  const Params p = resolve_params("squash", {}, "authors");
  EXPECT_EQ(p.profile, "authors");
  EXPECT_EQ(p.residual_metric, "authors");
  EXPECT_EQ(p.step, "line_search");
  EXPECT_EQ(p.mesh_height, 0.2);
  EXPECT_EQ(p.amg.strength_threshold, 0.0);
  EXPECT_EQ(p.amg.coarse_solver, "smoother");
  EXPECT_EQ(p.amg.jacobi_omega, "level0");
  EXPECT_EQ(p.amg.smoother.sweeps, 2);
  EXPECT_EQ(p.linear.tol, 1e-5);
  EXPECT_EQ(p.linear.max_iterations, 100);
  EXPECT_EQ(p.rtol, 1e-2);  // the scene's, untouched
  const Params q = resolve_params("squash", {"step=fixed", "mesh_height=0"}, "authors");
  EXPECT_EQ(q.step, "fixed");
  EXPECT_EQ(q.mesh_height, 0.0);
  const Params c = resolve_params("cloth_hang", {}, "authors");
  EXPECT_EQ(c.mesh_height, 0.0);  // the squash table does not apply
  EXPECT_EQ(c.step, "line_search");
  EXPECT_EQ(resolve_params("squash", {}).profile, "");
  EXPECT_THROW(resolve_params("squash", {}, "no_such_profile"), Error);
}

// The CLI: --profile reaches the run, `profile` is recorded and shown by report --format json,
// and the new datasets are written.
TEST(Profile, RecordedByRunAndReport) {
  const test::TempDir dir;
  const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";
  const std::string out = dir / "p.h5", plain = dir / "plain.h5", json = dir / "r.json";
  const std::string common = " run --scene squash --set resolution=4 --set max_iterations=3 --solver xpbd-authors,cholmod";
  ASSERT_EQ(std::system((bench + common + " --profile authors --out " + out + " >/dev/null 2>&1").c_str()), 0);
  ASSERT_EQ(std::system((bench + common + " --out " + plain + " >/dev/null 2>&1").c_str()), 0);
  const auto runs = read_runs(out, true);
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& r : runs) {
    EXPECT_EQ(test::attr_string(r, "profile"), "authors");
    EXPECT_EQ(test::attr_string(r, "step"), "line_search");
    EXPECT_TRUE(r.datasets.count("authors_dual_residual"));
    EXPECT_TRUE(r.datasets.count("authors_relative_dual_residual"));
  }
  EXPECT_TRUE(test::run_of(runs, "cholmod").datasets.count("step_length"));
  EXPECT_FALSE(test::run_of(runs, "xpbd-authors").datasets.count("step_length"));
  EXPECT_EQ(test::attr_string(read_runs(plain)[0], "profile"), "");
  ASSERT_EQ(std::system((bench + " report " + out + " --format json >" + json).c_str()), 0);
  std::stringstream text;
  text << std::ifstream(json).rdbuf();
  EXPECT_NE(text.str().find("\"profile\": \"authors\""), std::string::npos);
}

// A run saved after frame 1 and resumed from the file ends bit for bit where the uninterrupted
// run ends; the same frame run from the scene's start does not.
TEST(StateCheckpoint, LoadedRunContinuesTheSavedTrajectory) {
  const test::TempDir dir;
  const std::string bench = "OMP_NUM_THREADS=1 " + std::string(XB_BINARY_DIR) + "/xpbd-bench";
  const std::string base = " run --scene squash --set resolution=4 --solver xpbd-gs";
  const std::string state = dir / "s.h5", full = dir / "full.h5", resumed = dir / "resumed.h5", fresh = dir / "fresh.h5";
  auto run = [&](const std::string& args) { return std::system((bench + base + args + " >/dev/null 2>&1").c_str()); };
  ASSERT_EQ(run(" --frames 3 --save-state " + state + " --frame-of-state 1 --out " + full), 0);
  ASSERT_EQ(run(" --frames 1 --load-state " + state + " --out " + resumed), 0);
  ASSERT_EQ(run(" --frames 1 --out " + fresh), 0);
  auto positions = [](const std::string& f) {
    return std::get<std::vector<double>>(read_runs(f, true)[0].datasets.at("final_positions"));
  };
  EXPECT_EQ(positions(full), positions(resumed));
  EXPECT_NE(positions(fresh), positions(resumed));
  const auto frames = std::get<std::vector<long long>>(read_runs(resumed, true)[0].datasets.at("frame"));
  EXPECT_EQ(frames.front(), 2);  // numbered on from the saved frame
  EXPECT_EQ(read_state(state).frame, 2);
  EXPECT_NE(run(" --load-state " + full + " --out " + fresh), 0);  // a results file is not a state
}
