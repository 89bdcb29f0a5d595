// medit .mesh reader: any bytes end in a mesh or an xb::Error.
#include "fuzz_input.hpp"

#include "problems/meshes/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = xb_fuzz::write_file("input.mesh", xb_fuzz::as_text(data, size));
  xb_fuzz::expect_clean([&] {
    xb::MeshReadReport report;  // takes the notes the reader would otherwise print
    xb::read_tet_mesh(path, &report);
  });
  return 0;
}
