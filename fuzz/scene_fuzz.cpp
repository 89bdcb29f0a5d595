// TOML scene reader: the file as `run --scene FILE` reads it (resolve_params: every key set and
// checked, then the cross-field checks). Building the scene's problem is not reading and is left
// out: a valid scene may ask for any size of mesh.
#include "fuzz_input.hpp"

#include "harness/cli/run_setup.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = xb_fuzz::write_file("scene.toml", xb_fuzz::as_text(data, size));
  xb_fuzz::expect_clean([&] { xb::resolve_params(path, {}, ""); });
  return 0;
}
