// The checks every reader ends in, and the reader chosen by extension.
#include "mesh_io.hpp"
#include "text_lines.hpp"

#include <algorithm>
#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

using namespace mesh_text;

void finish_tet_mesh(TetMesh& mesh, const std::string& vertex_file, const std::vector<int>& vertex_line,
                     const std::string& tet_file, const std::vector<int>& tet_line, MeshReadReport* report) {
  const long long nv = mesh.vertices.cols();
  const size_t nt = mesh.tets.size();
  auto vwhere = [&](long long i) { return vertex_file + ":" + std::to_string(vertex_line.at(i)); };
  auto twhere = [&](size_t t) { return tet_file + ":" + std::to_string(tet_line.at(t)); };
  if (nv == 0) throw Error(vertex_file + ": the mesh has no vertices");
  if (nt == 0) throw Error(tet_file + ": the mesh has no tetrahedra");
  for (long long i = 0; i < nv; ++i)
    if (!mesh.vertices.col(i).allFinite()) throw Error(vwhere(i) + ": vertex has a non-finite coordinate");
  std::vector<char> used(nv, 0);
  for (size_t t = 0; t < nt; ++t) {
    const auto& e = mesh.tets[t];
    for (int k = 0; k < 4; ++k) {
      if (e[k] < 0 || e[k] >= nv)
        throw Error(twhere(t) + ": tetrahedron refers to vertex " + std::to_string(e[k]) + " (0-based), out of range [0, " +
                    std::to_string(nv) + ")");
      for (int l = 0; l < k; ++l)
        if (e[k] == e[l]) throw Error(twhere(t) + ": tetrahedron repeats a vertex (degenerate)");
      used[e[k]] = 1;
    }
  }
  for (long long i = 0; i < nv; ++i)
    if (!used[i]) throw Error(vwhere(i) + ": vertex is used by no tetrahedron (unreferenced vertices are an error)");

  std::vector<double> vol(nt);
  for (size_t t = 0; t < nt; ++t) {
    const auto& e = mesh.tets[t];
    vol[t] = tet_volume(mesh.vertices.col(e[0]), mesh.vertices.col(e[1]), mesh.vertices.col(e[2]), mesh.vertices.col(e[3]));
  }
  std::vector<double> absv(nt);
  for (size_t t = 0; t < nt; ++t) absv[t] = std::abs(vol[t]);
  std::nth_element(absv.begin(), absv.begin() + nt / 2, absv.end());
  const double median = absv[nt / 2];
  if (!(median > 0)) throw Error(tet_file + ": at least half of the tetrahedra have zero volume (a flat mesh?)");
  const double limit = degenerate_volume_ratio * median;
  int flipped = 0;
  for (size_t t = 0; t < nt; ++t) {
    if (!(std::abs(vol[t]) > limit)) {
      std::ostringstream os;
      os << twhere(t) << ": tetrahedron is degenerate: |volume| " << std::abs(vol[t]) << " <= " << degenerate_volume_ratio
         << " x the median volume " << median;
      throw Error(os.str());
    }
    if (vol[t] < 0) {
      std::swap(mesh.tets[t][1], mesh.tets[t][2]);
      ++flipped;
    }
  }
  if (report) report->flipped = flipped;
}

TetMesh read_tet_mesh(const std::string& path, MeshReadReport* report) {
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw Error(path + ": is a directory, not a mesh file");
  const std::string ext = p.extension().string();
  if (ext == ".node" || ext == ".ele") {
    fs::path node = p, ele = p;
    node.replace_extension(".node");
    ele.replace_extension(".ele");
    for (const fs::path& f : {node, ele}) {
      std::error_code ec;
      if (fs::is_directory(f, ec)) throw Error(path + ": the TetGen pair needs the file " + f.string() + ", which is a directory");
      if (!fs::is_regular_file(f, ec)) throw Error(path + ": the TetGen pair needs " + f.string() + ", which does not exist");
    }
    return read_tetgen(node.string(), ele.string(), report);
  }
  if (ext == ".msh") return read_gmsh(path, report);
  if (ext == ".mesh") return read_medit(path, report);
  throw Error(path + ": unknown mesh format '" + ext + "' (valid: .node/.ele (TetGen), .msh (gmsh 2.2/4.1 ASCII), .mesh (medit))");
}

}  // namespace xb
