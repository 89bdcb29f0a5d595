// Captured-system reader (`solve --system FILE.h5`): any bytes end in a system or an xb::Error.
// Crashes inside libhdf5 itself are told apart from ours as fuzz/README.md describes.
#include "fuzz_input.hpp"

#include "harness/io/system_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = xb_fuzz::write_file("system.h5", xb_fuzz::as_text(data, size));
  xb_fuzz::expect_clean([&] { xb::read_system_h5(path); });
  return 0;
}
