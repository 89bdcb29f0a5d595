// The form axis through the commands: captured systems carry the primal data, `solve` and `run`
// take --form, every run records the form it used, and form=primal is refused where it cannot
// exist (compliance 0).
#include "harness/cli/commands.hpp"
#include "harness/cli/report.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/io/run_record.hpp"
#include "harness/sim/simulation.hpp"
#include "harness/io/system_io.hpp"
#include "core/error.hpp"
#include "problems/scene.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::test;

namespace {
std::vector<RunRecord> runs_with(const std::vector<RunRecord>& runs, const std::string& solver) {
  std::vector<RunRecord> v;
  for (const auto& r : runs)
    if (attr_string(r, "solver") == solver) v.push_back(r);
  return v;
}
}  // namespace

TEST(PrimalCli, CapturedSystemCarriesThePrimalFormAndSolvesInBoth) {
  TempDir dir;
  const std::string prefix = dir / "sys";
  ASSERT_EQ(cmd_capture({"--scene", "bar_hang", "--set", "resolution=2", "--set", "prestretch=1.05", "--frame", "0",
                         "--iteration", "1", "--out", prefix}),
            0);
  const CapturedSystem s = read_system_h5(prefix + ".h5");
  ASSERT_TRUE(s.has_primal());
  EXPECT_EQ(s.graph.num_constraints(), s.A.rows());
  EXPECT_EQ(s.alpha_tilde.size(), s.A.rows());
  EXPECT_EQ(s.x.cols(), s.graph.num_particles());
  // K's Matrix Market file is the K assembled from the file's J.
  PrimalSystem ps(s.graph);
  ps.fill(s.grad, s.alpha_tilde);
  const SparseMatrix K = read_matrix_market_matrix(prefix + "_K.mtx");
  ASSERT_EQ(K.rows(), ps.rows());
  EXPECT_LE((Eigen::MatrixXd(K) - Eigen::MatrixXd(ps.K())).cwiseAbs().maxCoeff(),
            1e-12 * Eigen::MatrixXd(ps.K()).cwiseAbs().maxCoeff());

  const std::string out = dir / "solve.h5";
  ASSERT_EQ(cmd_solve({"--system", prefix + ".h5", "--solver", "jacobi-pcg,cholmod", "--form", "dual,primal", "--out", out}), 0);
  const auto runs = read_runs(out, false);
  ASSERT_EQ(runs.size(), 4u);
  for (const std::string solver : {"jacobi-pcg", "cholmod"}) {
    const auto rs = runs_with(runs, solver);
    ASSERT_EQ(rs.size(), 2u);
    EXPECT_EQ(attr_string(rs[0], "form_used"), "dual");
    EXPECT_EQ(attr_string(rs[1], "form_used"), "primal");
    for (const auto& r : rs) {
      EXPECT_EQ(attr_string(r, "status"), "ok") << r.name;
      // The harness's own residual ‖b − AΔλ‖/‖b‖, recomputed from the recorded Δλ.
      EXPECT_LE(attr_double(r, "final_relative_residual"), 1.2e-8) << r.name;
      EXPECT_LE(attr_double(r, "error_vs_direct"), 1e-5) << r.name;
    }
    EXPECT_GT(attr_double(rs[1], "primal_rows"), 0) << solver;
  }
}

TEST(PrimalCli, RunRecordsTheFormAndBothFormsTakeTheSameSteps) {
  TempDir dir;
  const std::string out = dir / "run.h5";
  ASSERT_EQ(cmd_run({"--scene", "cloth_hang", "--set", "resolution=8", "--solver", "xpbd-gs,cholmod", "--form", "dual,primal",
                     "--out", out}),
            0);
  const auto runs = read_runs(out, true);
  ASSERT_EQ(runs.size(), 3u);  // the local sweep runs once
  EXPECT_EQ(attr_string(runs_with(runs, "xpbd-gs")[0], "form_used"), "none");
  EXPECT_FALSE(runs_with(runs, "xpbd-gs")[0].datasets.count("fill_time"));
  const auto chol = runs_with(runs, "cholmod");
  ASSERT_EQ(chol.size(), 2u);
  EXPECT_EQ(attr_string(chol[0], "form_used"), "dual");
  EXPECT_EQ(attr_string(chol[1], "form_used"), "primal");
  // The same Δλ either way, so the same outer iterations to the same tolerance.
  for (const auto& r : chol) EXPECT_EQ(attr_string(r, "status"), "ok") << r.name;
  EXPECT_EQ(attr_double(chol[0], "outer_iterations"), attr_double(chol[1], "outer_iterations"));
  // Each step's fill of A (dual, before the setup) or K (primal, inside the setup) is timed.
  for (const auto& r : chol) {
    const auto& fill = std::get<std::vector<double>>(r.datasets.at("fill_time"));
    const auto& step = std::get<std::vector<double>>(r.datasets.at("step_time"));
    const auto& setup = std::get<std::vector<double>>(r.datasets.at("linear_setup_time"));
    const auto& it = std::get<std::vector<long long>>(r.datasets.at("iteration"));
    ASSERT_EQ(fill.size(), step.size()) << r.name;
    for (size_t i = 0; i < fill.size(); ++i) {
      if (it[i] == 0) {
        EXPECT_EQ(fill[i], 0.0) << r.name;
        continue;
      }
      EXPECT_GT(fill[i], 0.0) << r.name << " entry " << i;
      EXPECT_LE(fill[i], step[i]) << r.name << " entry " << i;
      if (r.name == chol[1].name) {
        EXPECT_LE(fill[i], setup[i]) << "entry " << i;
      }
    }
  }
}

TEST(PrimalCli, PrimalIsRefusedAtZeroComplianceAndAutoTakesDual) {
  TempDir dir;
  const std::string out = dir / "rigid.h5";
  try {
    cmd_run({"--scene", "cloth_hang", "--set", "resolution=4", "--variant", "rigid", "--solver", "cholmod", "--form", "primal",
             "--out", out});
    FAIL() << "form=primal with compliance 0 was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("form=primal needs every constraint compliant"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  ASSERT_EQ(cmd_run({"--scene", "cloth_hang", "--set", "resolution=4", "--variant", "rigid", "--solver", "cholmod", "--form",
                     "auto", "--out", out}),
            0);
  EXPECT_EQ(attr_string(read_runs(out, false).at(0), "form_used"), "dual");
  // Soft constraints: auto takes primal.
  ASSERT_EQ(cmd_run({"--scene", "cloth_hang", "--set", "resolution=4", "--solver", "cholmod", "--set", "form=auto", "--out", out}), 0);
  EXPECT_EQ(attr_string(read_runs(out, false).at(0), "form_used"), "primal");
}

TEST(PrimalCli, UnknownFormIsAClearError) {
  TempDir dir;
  try {
    cmd_run({"--scene", "cloth_hang", "--solver", "cholmod", "--form", "diagonal", "--out", dir / "x.h5"});
    FAIL() << "an unknown form was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown form 'diagonal'"), std::string::npos) << e.what();
  }
}
