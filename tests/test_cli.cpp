// The end-to-end harness through its CLI: the stalling that motivates the paper, the report's
// JSON contract, and bad input (one line, non-zero exit, nothing written or lost).
#include "harness/recorder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {
const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";

struct Result {
  int code;
  std::string out, err;
};

Result sh(const std::string& args) {
  const fs::path dir = fs::temp_directory_path() / ("xb_cli_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string out = (dir / "out.txt").string(), err = (dir / "err.txt").string();
  const int st = std::system((bench + " " + args + " >" + out + " 2>" + err).c_str());
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
