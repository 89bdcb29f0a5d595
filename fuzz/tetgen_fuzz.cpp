// TetGen .node/.ele pair: one input holds both files, the .node text, a line "@@ele", then the
// .ele text (no such line: all of it is the .node file and the .ele file is empty).
#include "fuzz_input.hpp"

#include "problems/meshes/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view all = xb_fuzz::as_text(data, size);
  constexpr std::string_view sep = "\n@@ele\n";
  const size_t cut = all.find(sep);
  const std::string_view node = all.substr(0, cut);
  const std::string_view ele = cut == std::string_view::npos ? std::string_view() : all.substr(cut + sep.size());
  xb_fuzz::write_file("input.node", node);
  xb_fuzz::write_file("input.ele", ele);
  xb_fuzz::expect_clean([&] {
    xb::MeshReadReport report;  // takes the notes the reader would otherwise print
    xb::read_tet_mesh(xb_fuzz::work_dir() + "/input.node", &report);
  });
  return 0;
}
