// `report`'s simulation table shows each run's own convergence measure (issue 36): relative ‖∇E‖
// under step = newton, whose dual residual is rounding over rounding, the dual residual under XPBD;
// the position error and the reference's verdict where the run has a reference.
#include "harness/cli/commands.hpp"
#include "harness/cli/report.hpp"
#include "harness/io/recorder.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <sstream>

using namespace xb;
using namespace xb::test;

namespace {
// The simulation table of `report FILE` as {run name: {column: cell}} (columns are separated by
// at least two spaces; no cell holds two).
std::map<std::string, std::map<std::string, std::string>> simulation_table(const std::string& file) {
  testing::internal::CaptureStdout();
  print_report(file, "table");
  std::istringstream out(testing::internal::GetCapturedStdout());
  std::map<std::string, std::map<std::string, std::string>> rows;
  std::vector<std::string> header;
  const std::regex gap("  +");
  for (std::string line; std::getline(out, line) && !line.empty();) {
    std::vector<std::string> cells(std::sregex_token_iterator(line.begin(), line.end(), gap, -1), {});
    if (header.empty()) {
      header = cells;
      continue;
    }
    if (cells.size() != header.size()) continue;  // the legend lines
    for (size_t c = 0; c < cells.size(); ++c) rows[cells[0]][header[c]] = cells[c];
  }
  return rows;
}

std::string text3(double v) { return attr_value_text(AttrValue{v}, 3); }
}  // namespace

TEST(Report, NewtonShowsItsEnergyGradientAndXpbdItsDualResidual) {
  TempDir dir;
  const std::string out = dir / "runs.h5";
  ASSERT_EQ(cmd_run({"--scene", "twist_bar", "--solver", "cholmod", "--set", "resolution=2", "--set", "stiffness=7e9",
                     "--set", "max_iterations=5", "--reference", "--out", out}),
            0);
  ASSERT_EQ(cmd_run({"--scene", "twist_bar", "--solver", "cholmod", "--profile", "newton", "--set", "resolution=2",
                     "--set", "stiffness=7e9", "--set", "rtol=1e-6", "--reference", "--out", dir / "newton.h5"}),
            0);
  const auto xpbd = read_runs(out, true).at(0);
  const auto newton = read_runs(dir / "newton.h5", true).at(0);
  const auto xpbd_rows = simulation_table(out), newton_rows = simulation_table(dir / "newton.h5");
  const auto& x = xpbd_rows.at(xpbd.name);
  const auto& n = newton_rows.at(newton.name);

  // XPBD: the dual residual, as the run's attributes have it.
  EXPECT_EQ(x.at("measure"), "dual");
  EXPECT_EQ(x.at("relative"), text3(attr_double(xpbd, "relative_dual_residual")));
  EXPECT_EQ(x.at("final"), text3(attr_double(xpbd, "final_dual_residual")));

  // Newton: ‖∇E‖ relative to its value at x̃, recomputed here from the datasets (g = h²∇E):
  // converged to the rtol it was given, whatever its dual residual says.
  EXPECT_EQ(n.at("measure"), "|grad E|");
  const auto& g = std::get<std::vector<double>>(newton.datasets.at("primal_residual"));
  const double h = attr_double(newton, "dt") / attr_double(newton, "substeps");
  const double relative = g.back() / g.front(), absolute = g.back() / (h * h);
  EXPECT_LE(relative, 1e-6);
  EXPECT_NEAR(attr_double(newton, "final_relative_convergence"), relative, 1e-12 * relative);
  EXPECT_NEAR(attr_double(newton, "final_convergence"), absolute, 1e-12 * absolute);
  EXPECT_EQ(n.at("relative"), text3(relative));
  EXPECT_NE(n.at("relative"), text3(attr_double(newton, "relative_dual_residual")));
  // The same quantity by another path: the relative Newton residual √(‖g‖² + ‖h‖²)/‖g(x̃)‖, h ≈ 0.
  EXPECT_NEAR(attr_double(newton, "final_relative_newton_residual"), relative, 1e-6 * relative + 1e-15);

  // Both have a reference: its verdict, its certificate and the position error, as recorded.
  EXPECT_EQ(n.at("reference"), "converged");
  EXPECT_EQ(n.at("certificate"), "error <= " + text3(attr_double(newton, "reference_error_estimate")) + ", trusted to " +
                                     text3(attr_double(newton, "reference_certified_threshold")));
  EXPECT_EQ(n.at("final_position_error"), text3(attr_double(newton, "final_position_error")));
  EXPECT_EQ(x.at("final_position_error"), text3(attr_double(xpbd, "final_position_error")));
}

// Records made by hand: an unconverged reference is named with its count; a Newton run from
// before the convergence attributes shows its relative Newton residual, marked as such.
TEST(Report, UnconvergedReferenceAndOldNewtonFiles) {
  TempDir dir;
  auto run = [](const std::string& name) {
    RunRecord r;
    r.name = name;
    r.attrs["level"] = std::string("simulation");
    r.attrs["scene"] = std::string("squash");
    r.attrs["solver"] = std::string("mgpbd");
    r.attrs["status"] = std::string("ok");
    r.attrs["relative_dual_residual"] = 0.324;
    r.attrs["final_dual_residual"] = 1e-9;
    return r;
  };
  RunRecord unconverged = run("unconverged");  // numbered by the recorder: 0001_unconverged
  unconverged.attrs["convergence_measure"] = std::string("energy_gradient");
  unconverged.attrs["final_convergence"] = 2.0;
  unconverged.attrs["final_relative_convergence"] = 7.9e-8;
  unconverged.attrs["reference_substeps_unconverged"] = 2LL;
  unconverged.attrs["substeps_total"] = 3LL;
  unconverged.attrs["final_position_error"] = 0.5;
  unconverged.attrs["reference_substeps_uncertified"] = 1LL;
  RunRecord old = run("old");
  old.attrs["step"] = std::string("newton");
  old.attrs["final_relative_newton_residual"] = 3e-9;
  const std::string out = dir / "made.h5";
  append_runs(out, {unconverged, old}, true);
  const auto rows = simulation_table(out);
  EXPECT_EQ(rows.at("0001_unconverged").at("measure"), "|grad E|");
  EXPECT_EQ(rows.at("0001_unconverged").at("relative"), "7.9e-08");
  EXPECT_EQ(rows.at("0001_unconverged").at("reference"), "2 of 3 substeps unconverged");
  EXPECT_EQ(rows.at("0001_unconverged").at("certificate"), "uncertified in 1 of 3 substeps");
  EXPECT_EQ(rows.at("0002_old").at("measure"), "~|grad E|");
  EXPECT_EQ(rows.at("0002_old").at("relative"), "3e-09");
  EXPECT_EQ(rows.at("0002_old").at("reference"), "-");
}
