// The recorder writes only what the results schema lists (harness/io/schema.cpp): an unlisted
// name, a name of the other level or a value of the wrong type is refused before the file is touched.
#include "harness/io/recorder.hpp"
#include "harness/io/schema.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;
using namespace xb;

namespace {
RunRecord simulation_run() {
  RunRecord r;
  r.name = "cloth_hang_cg";
  r.attrs["level"] = std::string("simulation");
  r.attrs["status"] = std::string("ok");
  r.attrs["outer_iterations"] = 3LL;
  r.attrs["dt"] = 0.003;
  r.datasets["dual_residual"] = std::vector<double>{1.0, 0.5};
  return r;
}
}  // namespace

TEST(Recorder, WritesOnlyWhatTheSchemaLists) {
  const std::string out = (fs::temp_directory_path() / "xb_recorder_schema.h5").string();
  fs::remove(out);
  fs::remove_all(runs_folder(out));
  EXPECT_NO_THROW(append_runs(out, {simulation_run()}, true));
  EXPECT_EQ(count_runs(out), 1);
  const auto size = fs::file_size(out);

  RunRecord unknown = simulation_run();
  unknown.attrs["bogus"] = 1.0;
  RunRecord other_level = simulation_run();
  other_level.attrs["error_vs_direct"] = 1e-9;  // a linear run's attribute
  RunRecord wrong_type = simulation_run();
  wrong_type.attrs["outer_iterations"] = std::string("three");
  RunRecord wrong_param_type = simulation_run();
  wrong_param_type.attrs["dt"] = 3LL;
  RunRecord unknown_dataset = simulation_run();
  unknown_dataset.datasets["bogus"] = std::vector<double>{1.0};
  for (const RunRecord& r : {unknown, other_level, wrong_type, wrong_param_type, unknown_dataset})
    EXPECT_THROW(append_runs(out, {r}), std::logic_error);
  EXPECT_EQ(count_runs(out), 1);  // the file is as it was
  EXPECT_EQ(fs::file_size(out), size);
  fs::remove(out);
  fs::remove_all(runs_folder(out));
}
