// Captured-system reader (`solve --system FILE.h5`) on structure-aware inputs (fuzz/h5_edits.hpp):
// a system written by the harness, edited at schema level, must end in a system or an xb::Error,
// with every HDF5 object closed.
#include "fuzz_input.hpp"
#include "h5_edits.hpp"

#include "harness/io/system_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> names = {
      "/A", "/A/indptr", "/A/indices", "/A/data", "/b", "/J", "/J/indptr", "/J/indices", "/J/data",
      "/inverse_mass", "/alpha_tilde", "/positions", "kind", "rows", "nnz", "generator"};
  const std::string path = xb_fuzz::build_h5(XB_FUZZ_SEEDS "/system", "system.h5", names, data, size);
  if (path.empty()) return 0;  // not built (fuzz/h5_edits.hpp)
  xb_fuzz::expect_clean([&] { xb::read_system_h5(path); });
  xb_fuzz::expect_no_open_handles();
  return 0;
}
