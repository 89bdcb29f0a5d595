// Sweeps (spec validation, expansion, crash safety and resume through the real CLI) and the
// per-substep reference behind position_error.
#include "harness/cli/report.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/io/run_record.hpp"
#include "harness/io/recorder.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/simulation.hpp"
#include "harness/cli/sweep.hpp"
#include "core/error.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace fs = std::filesystem;
using namespace xb;

namespace {

const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("xb_test_sweep_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p.string();
}

// The θ_s sweep of the issue, with mgpbd once it is registered (cholmod ignores amg.* keys,
// so the spec is the same form either way).
std::string theta_solver() {
  const MethodInfo* m = find_method("mgpbd");
  return m && m->available ? "mgpbd" : "cholmod";
}

// A started CLI process with its stderr on a pipe.
struct Child {
  pid_t pid = -1;
  int err = -1;
  std::string text;  // stderr so far
};

Child spawn(const std::vector<std::string>& args) {
  int fds[2];
  EXPECT_EQ(pipe(fds), 0);
  Child c;
  c.pid = fork();
  if (c.pid == 0) {
    dup2(fds[1], STDERR_FILENO);
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, STDOUT_FILENO);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> argv{const_cast<char*>(bench.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(bench.c_str(), argv.data());
    _exit(127);
  }
  close(fds[1]);
  c.err = fds[0];
  return c;
}

// Reads stderr until `needle` appears (true) or the pipe closes (false); a hang guard of 5 min.
bool read_until(Child& c, const std::string& needle) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  char buf[4096];
  while (needle.empty() || c.text.find(needle) == std::string::npos) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    pollfd pfd{c.err, POLLIN, 0};
    if (poll(&pfd, 1, 200) <= 0) continue;
    const ssize_t n = read(c.err, buf, sizeof buf);
    if (n <= 0) return false;
    c.text.append(buf, static_cast<size_t>(n));
  }
  return true;
}

int finish(Child& c) {
  read_until(c, "");
  close(c.err);
  int st = 0;
  waitpid(c.pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string attr_string(const RunRecord& r, const std::string& k) {
  auto it = r.attrs.find(k);
  return it == r.attrs.end() ? "" : std::get<std::string>(it->second);
}

}  // namespace

TEST(SweepSpec, IssueExampleExpandsToOneRunPerPointAndSolver) {
  const auto d = temp_dir("example");
  const std::string spec = write(d / "s.toml", "scene = \"bar_hang\"\nsolvers = [\"" + theta_solver() +
                                                   "\", \"xpbd-gs\"]\nframes = 1\n[set]\nmax_iterations = 50\n"
                                                   "[grid]\n\"amg.strength_threshold\" = [0.0, 0.1, 0.25]\n");
  const SweepSpec s = parse_sweep_spec(spec);
  const auto jobs = expand_sweep(s);
  ASSERT_EQ(jobs.size(), 6u);
  std::set<std::string> keys;
  for (const auto& j : jobs) keys.insert(j.key);
  EXPECT_EQ(keys.size(), 6u);
  EXPECT_EQ(jobs[0].point_text, "amg.strength_threshold=0");
  EXPECT_EQ(jobs[2].point_text, "amg.strength_threshold=0.1");
  EXPECT_DOUBLE_EQ(jobs[5].params.amg.strength_threshold, 0.25);
  EXPECT_EQ(jobs[5].solver, "xpbd-gs");
  EXPECT_EQ(jobs[3].params.max_iterations, 50);
  EXPECT_EQ(jobs[3].params.resolution, 4);  // from the scene file
}

TEST(SweepSpec, CartesianProductRepeatsAndBaseHash) {
  const auto d = temp_dir("product");
  const std::string spec = write(d / "s.toml",
                                 "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\nrepeats = 2\n"
                                 "[grid]\nresolution = [4, 8]\ndt = [1e-3, 2e-3, 4e-3]\n");
  const auto jobs = expand_sweep(parse_sweep_spec(spec));
  ASSERT_EQ(jobs.size(), 12u);
  EXPECT_EQ(jobs[0].point_text, "resolution=4 dt=0.001");
  EXPECT_EQ(jobs[1].repeat, 1);
  EXPECT_EQ(jobs[2].point_text, "resolution=4 dt=0.002");
  EXPECT_EQ(jobs[11].point_text, "resolution=8 dt=0.004");
  EXPECT_EQ(jobs[11].params.resolution, 8);
  // Changing a fixed parameter changes the base (a different sweep); the grid does not.
  const std::string h1 = sweep_base_hash(parse_sweep_spec(spec));
  const std::string spec2 = write(d / "s2.toml",
                                  "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nomega = 0.5\n"
                                  "[grid]\nresolution = [4, 8, 16]\ndt = [1e-3]\n");
  const std::string spec3 = write(d / "s3.toml",
                                  "scene = \"cloth_hang\"\nsolvers = [\"cg\"]\n"
                                  "[grid]\nresolution = [16]\ndt = [1e-3]\n");
  EXPECT_NE(h1, sweep_base_hash(parse_sweep_spec(spec2)));
  EXPECT_EQ(h1, sweep_base_hash(parse_sweep_spec(spec3)));
}

// The figure specs of `make figures` (both sizes) are valid sweeps: parsed and expanded here so a
// renamed key or solver shows up in the tests, not an hour into `make figures`.
TEST(SweepSpec, FigureSpecsParse) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(std::string(XB_SOURCE_DIR) + "/figures"))
    for (const std::string size : {"default", "paper"}) {
      if (e.path().extension() != ".toml") continue;
      SCOPED_TRACE(e.path().string() + " at size " + size);
      const SweepSpec s = parse_sweep_spec(e.path().string(), size);
      EXPECT_FALSE(expand_sweep(s).empty());
      ++n;
    }
  EXPECT_GE(n, 24);  // 12 specs at 2 sizes, dual_primal and dual_primal_bar included
}

// A [sizes.NAME] table changes only what it names: its scalars and set.* / grid.* entries replace
// or add to the top-level ones; another size's table is ignored; an unknown size is refused.
TEST(SweepSpec, SizeTablesReplaceOnlyWhatTheyName) {
  const auto d = temp_dir("sizes");
  const std::string spec = write(d / "s.toml",
                                 "scene = \"bar_hang\"\nsolvers = [\"cholmod\"]\ntime_budget = 5\n"
                                 "[set]\nmax_iterations = 7\nstiffness = 1e7\n[grid]\nresolution = [2, 3]\n"
                                 "[sizes.big]\ntime_budget = 50\nset.max_iterations = 70\ngrid.resolution = [4]\n"
                                 "grid.\"amg.strength_threshold\" = [0.0, 0.5]\n"
                                 "[sizes.other]\nset.stiffness = 1e9\n");
  const SweepSpec small = parse_sweep_spec(spec);
  EXPECT_EQ(small.time_budget, 5);
  EXPECT_EQ(expand_sweep(small).size(), 2u);
  const SweepSpec big = parse_sweep_spec(spec, "big");
  EXPECT_EQ(big.time_budget, 50);
  const auto jobs = expand_sweep(big);
  ASSERT_EQ(jobs.size(), 2u);  // resolution [4] × θ [0, 0.5]
  EXPECT_EQ(jobs[0].params.resolution, 4);
  EXPECT_EQ(jobs[0].params.max_iterations, 70);
  EXPECT_EQ(jobs[0].params.stiffness, 1e7);  // [sizes.other] does not apply
  EXPECT_EQ(jobs[1].params.amg.strength_threshold, 0.5);
  try {
    parse_sweep_spec(spec, "huge");
    ADD_FAILURE() << "an unknown size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no size 'huge' (sizes: default, big, other)"), std::string::npos) << e.what();
  }
}

TEST(SweepSpec, BadSpecsFailWithTheLine) {
  const auto d = temp_dir("bad");
  const std::string head = "scene = \"bar_hang\"\nsolvers = [\"cholmod\"]\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {head + "colour = 3\n", "s.toml:3: unknown key 'colour'"},
      {head + "[set]\nnot_a_key = 1\n", "s.toml:4: unknown parameter 'not_a_key'"},
      {head + "[grid]\n\"amg.strength_threshold\" = []\n", "is an empty list"},
      {head + "[grid]\n\"amg.strength_threshold\" = [0.1, 2.0]\n", "out of range"},
      {head + "[grid]\n\"amg.smoother\" = [\"jacobi\", \"sor\"]\n", "must be one of"},
      {head + "[grid]\nresolution = 4\n", "must be a list"},
      {head + "[grid]\nresolution = [4, 4.0]\n", "twice"},
      {head + "[set]\nresolution = 4\n[grid]\nresolution = [4, 8]\n", "both fixed"},
      {head + "repeats = 0\n", "'repeats' must be an integer >= 1"},
      {head + "time_budget = -1\n", "'time_budget' must be >= 0"},
      {"scene = \"bar_hang\"\nsolvers = [\"cholmod\", \"no-such-solver\"]\n", "s.toml:2: unknown solver 'no-such-solver'"},
      {"scene = \"bar_hang\"\nsolvers = []\n", "'solvers' is empty"},
      {"scene = \"no_such_scene\"\nsolvers = [\"cholmod\"]\n", "unknown scene 'no_such_scene'"},
      {"solvers = [\"cholmod\"]\n", "missing 'scene'"},
      {"scene = \"bar_hang\"\n", "missing 'solvers'"},
  };
  for (const auto& [text, expect] : cases) {
    const std::string spec = write(d / "s.toml", text);
    try {
      expand_sweep(parse_sweep_spec(spec));
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what() << "\nexpected: " << expect;
    }
  }
}

TEST(SweepCli, BadSpecWritesNothingAndExitsNonZero) {
  const auto d = temp_dir("cli_bad");
  const std::string spec = write(d / "s.toml", "scene = \"bar_hang\"\nsolvers = [\"cholmod\"]\n[grid]\n"
                                               "\"amg.strength_threshold\" = [0.0, 1.5]\n");
  const std::string out = (d / "out.h5").string();
  Child c = spawn({"sweep", spec, "--out", out});
  EXPECT_EQ(finish(c), 2);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(c.text.find("out of range"), std::string::npos) << c.text;
  EXPECT_EQ(std::count(c.text.begin(), c.text.end(), '\n'), 1) << c.text;
}

// The issue's acceptance test: a 3-point θ_s sweep killed with SIGKILL during its second run,
// then rerun, ends with exactly three readable runs, the first not redone.
TEST(SweepCli, SigkillDuringSecondRunThenResume) {
  const auto d = temp_dir("kill");
  // Each run lasts its time budget (no tolerance can be met), so the second run is surely in
  // progress right after its start line; a run over its budget is a recorded status like any other.
  const std::string spec = write(d / "theta.toml", "scene = \"bar_hang\"\nsolvers = [\"" + theta_solver() +
                                                       "\"]\nframes = 1\ntime_budget = 1.5\n[set]\nthreads = 1\n"
                                                       "max_iterations = 100000000\nrtol = 0\natol = 0\n[grid]\n"
                                                       "\"amg.strength_threshold\" = [0.0, 0.1, 0.25]\n");
  const std::string out = (d / "theta.h5").string();

  Child first = spawn({"sweep", spec, "--out", out});
  ASSERT_TRUE(read_until(first, "[2/3]")) << first.text;
  ASSERT_EQ(kill(first.pid, SIGKILL), 0);
  int st = 0;
  waitpid(first.pid, &st, 0);
  close(first.err);
  ASSERT_TRUE(WIFSIGNALED(st) && WTERMSIG(st) == SIGKILL);

  // Killed mid-run: the file holds the first run, complete.
  auto runs = read_runs(out, true);
  ASSERT_EQ(runs.size(), 1u);
  const std::string first_name = runs[0].name;
  const std::string first_created = attr_string(runs[0], "created");
  const std::string first_key = attr_string(runs[0], "sweep_key");
  EXPECT_EQ(attr_string(runs[0], "sweep_point"), "amg.strength_threshold=0");
  EXPECT_EQ(attr_string(runs[0], "status"), "over_budget");

  Child again = spawn({"sweep", spec, "--out", out});
  ASSERT_EQ(finish(again), 0) << again.text;
  EXPECT_NE(again.text.find("1 already in"), std::string::npos) << again.text;

  runs = read_runs(out, true);  // every run readable, datasets included
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0].name, first_name);
  EXPECT_EQ(attr_string(runs[0], "created"), first_created);
  EXPECT_EQ(attr_string(runs[0], "sweep_key"), first_key);
  std::set<std::string> points;
  for (const auto& r : runs) {
    points.insert(attr_string(r, "sweep_point"));
    EXPECT_EQ(attr_string(r, "sweep_params"), "amg.strength_threshold");
    EXPECT_FALSE(std::get<std::vector<double>>(r.datasets.at("dual_residual")).empty());
  }
  EXPECT_EQ(points, (std::set<std::string>{"amg.strength_threshold=0", "amg.strength_threshold=0.1",
                                           "amg.strength_threshold=0.25"}));

  // A third call has nothing left to do.
  Child third = spawn({"sweep", spec, "--out", out});
  ASSERT_EQ(finish(third), 0) << third.text;
  EXPECT_NE(third.text.find("3 already in"), std::string::npos) << third.text;
  EXPECT_EQ(count_runs(out), 3);
  fs::remove_all(d);
}

TEST(SweepCli, AFileOfAnotherSweepIsRefused) {
  const auto d = temp_dir("other");
  const std::string a = write(d / "a.toml", "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nresolution = 4\n"
                                            "max_iterations = 5\n[grid]\nomega = [1.0]\n");
  const std::string b = write(d / "b.toml", "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nresolution = 5\n"
                                            "max_iterations = 5\n[grid]\nomega = [1.0]\n");
  const std::string out = (d / "o.h5").string();
  Child c = spawn({"sweep", a, "--out", out});
  ASSERT_EQ(finish(c), 0) << c.text;
  Child c2 = spawn({"sweep", b, "--out", out});
  EXPECT_EQ(finish(c2), 2);
  EXPECT_NE(c2.text.find("another sweep"), std::string::npos) << c2.text;
  EXPECT_EQ(count_runs(out), 1);
  fs::remove_all(d);
}

// The reference is the substep solved to 1e-10 by the direct method from x̃: the error is 1 at
// x̃ by definition, and a run of the same direct method converged to rtol 1e-8 lands on it.
TEST(Reference, PositionErrorIsOneAtPredictionAndVanishesForConvergedDirectSolve) {
  Params p;
  load_scene_file(resolve_scene("bar_hang"), p);  // starts prestretched: cholmod converges fast
  p.resolution = 2;
  p.frames = 1;
  p.rtol = 1e-8;
  p.threads = 1;
  // The reference is the dual CHOLMOD iteration: the same path to round-off only in the dual form
  // (the primal recovery Δλ = α̃⁻¹(b − JΔx) loses digits on the stiff bar: 2e-4 apart after 35 steps).
  p.form = "dual";
  p.reference_method = "xpbd";  // XPBD's fixed point (the default here is Newton's: tests/harness/sim/test_newton.cpp)
  const Problem prob = build_problem(p);
  RunOptions opt;
  opt.reference = true;
  const RunResult direct = run_simulation(prob, p, "cholmod", opt);
  ASSERT_EQ(direct.status, "ok") << direct.message;
  const IterationLog& L = direct.log;
  ASSERT_EQ(L.position_error.size(), L.dual_residual.size());
  ASSERT_EQ(L.reference_status.size(), 1u);
  EXPECT_EQ(L.reference_status[0], "converged");
  EXPECT_LT(L.reference_relative_dual_residual[0], 1e-10);
  EXPECT_GT(L.reference_iterations[0], 1);
  EXPECT_NEAR(L.position_error.front(), 1.0, 1e-12);
  EXPECT_LT(L.position_error.back(), 1e-6);
  EXPECT_GT(L.position_error[1], L.position_error.back());
  // The record carries it.
  const RunRecord rec = make_simulation_record("r", p, "cholmod", direct);
  EXPECT_TRUE(rec.datasets.count("position_error"));
  EXPECT_LT(std::get<double>(rec.attrs.at("reference_dual_residual")), 1e-10);

  // One Gauss-Seidel sweep per iteration stays far from it on this stiff bar; the reference is
  // recomputed for every substep (two frames: two references, error 1 at each x̃).
  p.max_iterations = 10;
  p.frames = 2;
  const RunResult gs = run_simulation(prob, p, "xpbd-gs", opt);
  ASSERT_EQ(gs.log.reference_status.size(), 2u);
  ASSERT_EQ(gs.log.position_error.size(), gs.log.iteration.size());
  for (size_t i = 0; i < gs.log.iteration.size(); ++i)
    if (gs.log.iteration[i] == 0) {
      EXPECT_NEAR(gs.log.position_error[i], 1.0, 1e-12);
    }
  EXPECT_GT(gs.log.position_error[10], 1e-2);
  // Without the option nothing is logged.
  EXPECT_TRUE(run_simulation(prob, p, "xpbd-gs").log.position_error.empty());
}
