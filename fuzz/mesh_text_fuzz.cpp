// The gmsh (.msh 2.2 and 4.1 ASCII) and medit (.mesh) readers, one target each (fuzz/CMakeLists.txt
// sets XB_FUZZ_MESH_EXT): any bytes end in a mesh or an xb::Error. The extension picks the reader.
#include "fuzz_input.hpp"

#include "problems/meshes/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = xb_fuzz::write_file("input" XB_FUZZ_MESH_EXT, xb_fuzz::as_text(data, size));
  xb_fuzz::expect_clean([&] {
    xb::MeshReadReport report;  // takes the notes the reader would otherwise print
    xb::read_tet_mesh(path, &report);
  });
  return 0;
}
