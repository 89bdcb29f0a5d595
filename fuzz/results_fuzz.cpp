// Results-file reader: `report` in both formats (its table and JSON go nowhere), and the runs
// with their datasets as the other readers of results files take them.
#include "fuzz_input.hpp"

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
  const std::string path = xb_fuzz::write_file("results.h5", xb_fuzz::as_text(data, size));
  static NullBuffer null;
  std::streambuf* const out = std::cout.rdbuf(&null);
  xb_fuzz::expect_clean([&] { xb::print_report(path, "table"); });
  xb_fuzz::expect_clean([&] { xb::print_report(path, "json"); });
  xb_fuzz::expect_clean([&] { xb::read_runs(path, true); });
  std::cout.rdbuf(out);
  return 0;
}
