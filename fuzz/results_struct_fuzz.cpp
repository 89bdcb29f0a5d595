// Results-file readers on structure-aware inputs (fuzz/h5_edits.hpp): results written by the
// harness, edited at schema level, read as `report` (table, JSON) and as read_runs with datasets
// (skipping unreadable runs, as `report` does);
// each must end in success or an xb::Error, with every HDF5 object closed.
#include "fuzz_input.hpp"
#include "h5_edits.hpp"

#include "harness/cli/report.hpp"
#include "harness/io/recorder.hpp"

#include <iostream>
#include <streambuf>

namespace {
struct NullBuffer : std::streambuf {
  int overflow(int c) override { return c; }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> names = {
      "/runs", "/runs/0001_x", "/runs/0001_mass_chain_cholmod/linear_history/offset", "level", "status", "scene",
      "solver", "load_average", "cpu_count", "omp_wait_policy", "schema_version", "generator", "wall_time"};
  const std::string path = xb_fuzz::build_h5(XB_FUZZ_SEEDS "/results", "results.h5", names, data, size);
  if (path.empty()) return 0;  // not built (fuzz/h5_edits.hpp)
  static NullBuffer null;
  std::streambuf* const out = std::cout.rdbuf(&null);
  xb_fuzz::expect_clean([&] { xb::print_report(path, "table"); });
  xb_fuzz::expect_clean([&] { xb::print_report(path, "json"); });
  xb_fuzz::expect_clean([&] {
    std::vector<std::string> skipped;  // every readable run's datasets, past unreadable runs
    xb::read_runs(path, true, &skipped);
  });
  std::cout.rdbuf(out);
  xb_fuzz::expect_no_open_handles();
  return 0;
}
