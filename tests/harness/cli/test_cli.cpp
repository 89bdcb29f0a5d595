// The end-to-end harness through its CLI: the stalling that motivates the paper, the report's
// JSON contract, and bad input (one line, non-zero exit, nothing written or lost).
#include "harness/cli/wait_policy.hpp"
#include "harness/io/recorder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {
const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";

struct Result {
  int code;
  std::string out, err;
};

// env_prefix: e.g. "env -u OMP_WAIT_POLICY " to start the binary with a changed environment.
Result sh(const std::string& args, const std::string& env_prefix = "") {
  const fs::path dir = fs::temp_directory_path() / ("xb_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "out.txt").string(), err = (dir / "err.txt").string();
  const int st = std::system((env_prefix + bench + " " + args + " >" + out + " 2>" + err).c_str());
  auto slurp = [](const std::string& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  };
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, slurp(out), slurp(err)};
}

std::string tmpfile(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("xb_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return (dir / name).string();
}

double number(const xb::RunRecord& r, const std::string& k) {
  const auto& v = r.attrs.at(k);
  if (auto* d = std::get_if<double>(&v)) return *d;
  return static_cast<double>(std::get<long long>(v));
}
std::string text(const xb::RunRecord& r, const std::string& k) { return std::get<std::string>(r.attrs.at(k)); }
}  // namespace

// On the first substep of cloth_hang the global direct solve converges while one-sweep XPBD stalls.
TEST(Cli, ClothHangCholmodConvergesWhereXpbdGsStalls) {
  const std::string out = tmpfile("stall.h5");
  const Result r = sh("run --scene cloth_hang --solver cholmod,xpbd-gs --set max_iterations=100 --set rtol=1e-6 --out " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto runs = xb::read_runs(out, true);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(text(runs[0], "solver"), "cholmod");
  EXPECT_EQ(text(runs[0], "status"), "ok");
  EXPECT_LE(number(runs[0], "outer_iterations"), 20);
  EXPECT_LE(number(runs[0], "relative_dual_residual"), 1e-6);
  EXPECT_EQ(text(runs[1], "solver"), "xpbd-gs");
  EXPECT_EQ(text(runs[1], "status"), "max_iterations");
  EXPECT_EQ(number(runs[1], "outer_iterations"), 100);
  EXPECT_GT(number(runs[1], "relative_dual_residual"), 1e-3);
  // One log entry per evaluation: iteration 0 plus one per step.
  const auto& dual = std::get<std::vector<double>>(runs[1].datasets.at("dual_residual"));
  EXPECT_EQ(dual.size(), 101u);

  const Result j = sh("report " + out + " --format json");
  ASSERT_EQ(j.code, 0) << j.err;
  for (const char* key : {"\"scene\"", "\"solver\"", "\"status\"", "\"outer_iterations\"", "\"final_dual_residual\"",
                          "\"relative_dual_residual\"", "\"wall_time\"", "\"dt\"", "\"rtol\""})
    EXPECT_NE(j.out.find(key), std::string::npos) << key;
  EXPECT_EQ(j.out.front(), '[');
}

TEST(Cli, ListNamesScenesAndSolvers) {
  const Result r = sh("list");
  ASSERT_EQ(r.code, 0);
  for (const char* s : {"cloth_hang", "bar_hang", "xpbd-jacobi", "xpbd-gs", "cholmod", "cg", "jacobi-pcg"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s;
}

TEST(Cli, BadInputIsOneLineNonZeroAndWritesNothing) {
  const std::string out = tmpfile("bad.h5");
  const std::string bad_toml = tmpfile("bad.toml");
  std::ofstream(bad_toml) << "scene = \"cloth_hang\"\nresolution = [1, 2\n";
  const std::string neg_toml = tmpfile("neg.toml");
  std::ofstream(neg_toml) << "scene = \"cloth_hang\"\ndt = -0.01\n";
  struct Case {
    std::string args, must_name;
  };
  const std::vector<Case> cases = {
      {"run --scene nosuch --solver cholmod --out " + out, "cloth_hang"},  // lists the valid ones
      {"run --scene cloth_hang --solver nosuch --out " + out, "xpbd-gs"},
      {"run --scene cloth_hang --solver cholmod --set nosuch=1 --out " + out, "nosuch"},
      {"run --scene " + bad_toml + " --solver cholmod --out " + out, "bad.toml:2"},
      {"run --scene cloth_hang --solver cholmod --set dt=-1 --out " + out, "'dt'"},
      {"run --scene " + neg_toml + " --solver cholmod --out " + out, "neg.toml:2"},
      {"run --scene cloth_hang --solver cholmod --set resolution=abc --out " + out, "resolution"},
      {"run --scene cloth_hang --solver cholmod --bogus --out " + out, "--bogus"},
      {"nosuchcommand", "nosuchcommand"},
      // capture writes XPBD's step only; step=newton needs the constraints' Hessians.
      {"capture --scene twist_bar --set resolution=2 --set step=newton --frame 0 --iteration 1 --out " + out, "step=newton"},
      {"run --scene twist_bar --solver cholmod --set resolution=2 --profile newton --set xpbd.geometric_stiffness=diagonal --out " + out,
       "xpbd.geometric_stiffness=full"},
  };
  for (const auto& c : cases) {
    fs::remove(out);
    const Result r = sh(c.args);
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.must_name), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  // An existing results file survives bad input untouched.
  ASSERT_EQ(sh("run --scene cloth_hang --solver cholmod --set resolution=4 --out " + out).code, 0);
  const auto before = fs::file_size(out);
  EXPECT_NE(sh("run --scene cloth_hang --solver nosuch --out " + out).code, 0);
  EXPECT_EQ(fs::file_size(out), before);
  EXPECT_EQ(xb::read_runs(out).size(), 1u);
}

// However the binary is started, its OpenMP threads sleep at barriers after a bounded spin
// (harness/cli/wait_policy.hpp sets OMP_WAIT_POLICY=passive and GOMP_SPINCOUNT=10000 and
// re-executes when no policy is set; a spin count or policy the user set is kept), and every run
// records the policy and spin count the runtime read, the load average at start and the CPU
// count. The recorded values are read before main, so `passive` from a binary started without the
// variable proves the re-exec.
TEST(Cli, RunRecordsWaitPolicyLoadAndCpusHoweverStarted) {
  struct Case {
    std::string env, policy, spin;
  };
  for (const Case& c : {Case{"env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT ", "passive", xb::kSpinCount},
                        Case{"env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=active ", "active", "default"},
                        Case{"env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=passive ", "passive", "default"},
                        Case{"env -u OMP_WAIT_POLICY GOMP_SPINCOUNT=500 ", "passive", "500"},
                        // A stale loop-guard marker (not this process's pid) must not stop the re-exec.
                        Case{"env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT XB_WAIT_POLICY_REEXEC=1 ", "passive", xb::kSpinCount}}) {
    const std::string out = tmpfile("policy.h5");
    fs::remove(out);
    const Result r = sh("run --scene cloth_hang --solver jacobi-pcg --set resolution=6 --out " + out, c.env);
    ASSERT_EQ(r.code, 0) << c.env << r.err;
    const auto runs = xb::read_runs(out);
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(text(runs[0], "omp_wait_policy"), c.policy) << c.env;
    EXPECT_EQ(text(runs[0], "omp_spin_count"), c.spin) << c.env;
    EXPECT_EQ(number(runs[0], "cpu_count"), static_cast<double>(::sysconf(_SC_NPROCESSORS_ONLN))) << c.env;
    const double load = number(runs[0], "load_average");
    EXPECT_GE(load, 0.0) << c.env;
    EXPECT_LT(load, 1e4) << c.env;
  }
  // The re-exec leaves exit code and output alone: bad input is still one line on stderr, exit 2.
  const Result bad = sh("nosuchcommand", "env -u OMP_WAIT_POLICY ");
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(bad.out, "");
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  const Result list = sh("list", "env -u OMP_WAIT_POLICY ");
  EXPECT_EQ(list.code, 0);
  EXPECT_NE(list.out.find("cloth_hang"), std::string::npos);
}

// `report` marks runs timed under load (load average at start above CPUs - 0.5) or with spinning
// threads, in the table and in JSON; a normal run and a run from before these attributes are not.
TEST(Cli, ReportFlagsRunsTimedUnderLoad) {
  auto run = [](const std::string& name, double load, const std::string& policy) {
    xb::RunRecord r;
    r.name = name;
    r.attrs["level"] = std::string("simulation");
    r.attrs["scene"] = std::string("cloth_hang");
    r.attrs["solver"] = std::string("cholmod");
    r.attrs["status"] = std::string("ok");
    r.attrs["wall_time"] = 1.25;
    if (load >= 0) {
      r.attrs["load_average"] = load;
      r.attrs["cpu_count"] = 4LL;
      r.attrs["omp_wait_policy"] = policy;
    }
    return r;
  };
  const std::string out = tmpfile("loaded.h5");
  xb::append_runs(out,
                  {run("loaded", 3.75, "passive"), run("quiet", 0.4, "passive"), run("old", -1, ""),
                   run("spinning", 0.2, "active"), run("edge", 3.5, "passive")},
                  true);
  const Result t = sh("report " + out);
  ASSERT_EQ(t.code, 0) << t.err;
  auto row = [&](const std::string& name) {
    const auto at = t.out.find(name);
    return at == std::string::npos ? std::string("(missing)") : t.out.substr(at, t.out.find('\n', at) - at);
  };
  EXPECT_NE(row("0001_loaded").find("* load 3.75 on 4 CPUs"), std::string::npos) << t.out;
  EXPECT_NE(row("0004_spinning").find("* wait policy active"), std::string::npos) << t.out;
  for (const char* ok : {"0002_quiet", "0003_old", "0005_edge"})  // 3.5 is not above 4 - 0.5
    EXPECT_EQ(row(ok).find('*'), std::string::npos) << row(ok);
  EXPECT_NE(t.out.find("timing"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("\n* timings suspect"), std::string::npos) << t.out;

  const Result j = sh("report " + out + " --format json");
  ASSERT_EQ(j.code, 0) << j.err;
  auto object = [&](const std::string& name) {
    const auto at = j.out.find("\"" + name + "\"");
    return at == std::string::npos ? std::string("(missing)") : j.out.substr(at, j.out.find('}', at) - at);
  };
  EXPECT_NE(object("0001_loaded").find("\"timing_suspect\": true"), std::string::npos) << j.out;
  EXPECT_NE(object("0001_loaded").find("\"load_average\": 3.75"), std::string::npos) << j.out;
  EXPECT_NE(object("0001_loaded").find("\"cpu_count\": 4"), std::string::npos) << j.out;
  EXPECT_NE(object("0004_spinning").find("\"timing_note\": \"wait policy active\""), std::string::npos) << j.out;
  EXPECT_NE(object("0002_quiet").find("\"timing_suspect\": false"), std::string::npos) << j.out;
  EXPECT_NE(object("0005_edge").find("\"timing_suspect\": false"), std::string::npos) << j.out;
  EXPECT_EQ(object("0003_old").find("timing"), std::string::npos) << j.out;

  // A file with only unflagged runs: the table is as before, no column, no legend.
  const std::string quiet = tmpfile("quiet.h5");
  xb::append_runs(quiet, {run("quiet", 0.4, "passive"), run("old", -1, "")}, true);
  const Result q = sh("report " + quiet);
  ASSERT_EQ(q.code, 0) << q.err;
  EXPECT_EQ(q.out.find("timing"), std::string::npos) << q.out;
  EXPECT_EQ(q.out.find('*'), std::string::npos) << q.out;
}
