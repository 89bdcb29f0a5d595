// TetGen .node + .ele.
#include "mesh_io.hpp"
#include "text_lines.hpp"

#include <algorithm>

namespace xb {

using namespace mesh_text;

TetMesh read_tetgen(const std::string& node_path, const std::string& ele_path, MeshReadReport* report) {
  TetMesh mesh;
  std::vector<int> vline, tline;
  std::vector<std::string_view> tok;
  int base = 0;
  long long nv = 0;
  {
    Lines L(node_path, true);
    const size_t bytes = file_size(node_path);
    L.require(tok, "the .node header (<#points> <dimension> <#attributes> <#boundary markers>)");
    if (tok.size() < 2 || tok.size() > 4)
      throw Error(L.where() + ": .node header: expected <#points> <dimension> [<#attributes> [<#boundary markers>]], found " +
                  std::to_string(tok.size()) + " values");
    nv = parse_count(tok[0], L.where(), "number of points", bytes);
    const long long dim = parse_int(tok[1], L.where(), "dimension");
    if (dim != 3) throw Error(L.where() + ": dimension " + std::to_string(dim) + " (only 3-D meshes are read)");
    const long long nattr = tok.size() > 2 ? parse_count(tok[2], L.where(), "number of attributes", bytes) : 0;
    const long long nmark = tok.size() > 3 ? parse_int(tok[3], L.where(), "number of boundary markers") : 0;
    if (nmark != 0 && nmark != 1) throw Error(L.where() + ": number of boundary markers must be 0 or 1");
    const size_t per = 4 + nattr + nmark;
    mesh.vertices.resize(3, nv);
    vline.resize(nv);
    for (long long i = 0; i < nv; ++i) {
      L.require(tok, "point " + std::to_string(i + 1) + " of " + std::to_string(nv));
      expect_tokens(L, tok, per, "point (<index> <x> <y> <z> [attributes] [marker])");
      const long long idx = parse_int(tok[0], L.where(), "point index");
      if (i == 0) {
        if (idx != 0 && idx != 1) throw Error(L.where() + ": the first point's index must be 0 or 1, found " + std::to_string(idx));
        base = static_cast<int>(idx);
      }
      if (idx != i + base)
        throw Error(L.where() + ": point index " + std::to_string(idx) + ", expected " + std::to_string(i + base) +
                    " (points must be numbered consecutively)");
      for (int c = 0; c < 3; ++c) mesh.vertices(c, i) = parse_double(tok[1 + c], L.where(), "coordinate");
      for (size_t a = 4; a < per; ++a) (void)parse_double(tok[a], L.where(), "attribute or marker");
      vline[i] = L.line();
    }
    if (L.next(tok)) throw Error(L.where() + ": more points than the " + std::to_string(nv) + " declared in the header");
  }
  {
    Lines L(ele_path, true);
    const size_t bytes = file_size(ele_path);
    L.require(tok, "the .ele header (<#tetrahedra> <nodes per tetrahedron> <#attributes>)");
    if (tok.size() < 2 || tok.size() > 3)
      throw Error(L.where() + ": .ele header: expected <#tetrahedra> <nodes per tetrahedron> [<#attributes>], found " +
                  std::to_string(tok.size()) + " values");
    const long long nt = parse_count(tok[0], L.where(), "number of tetrahedra", bytes);
    const long long npt = parse_int(tok[1], L.where(), "nodes per tetrahedron");
    if (npt != 4 && npt != 10) throw Error(L.where() + ": nodes per tetrahedron must be 4 or 10, found " + std::to_string(npt));
    const long long nattr = tok.size() > 2 ? parse_count(tok[2], L.where(), "number of attributes", bytes) : 0;
    const size_t per = 1 + npt + nattr;
    mesh.tets.resize(nt);
    tline.resize(nt);
    for (long long t = 0; t < nt; ++t) {
      L.require(tok, "tetrahedron " + std::to_string(t + 1) + " of " + std::to_string(nt));
      expect_tokens(L, tok, per, "tetrahedron (<index> <nodes> [attributes])");
      const long long idx = parse_int(tok[0], L.where(), "tetrahedron index");
      if (idx != t + base)
        throw Error(L.where() + ": tetrahedron index " + std::to_string(idx) + ", expected " + std::to_string(t + base) +
                    " (numbered consecutively from the .node file's first index " + std::to_string(base) + ")");
      for (int k = 0; k < 4; ++k) {  // corners first, also for 10-node tets
        const long long v = parse_int(tok[1 + k], L.where(), "vertex index");
        if (v < base || v >= nv + base)
          throw Error(L.where() + ": vertex index " + std::to_string(v) + " out of range [" + std::to_string(base) + ", " +
                      std::to_string(nv + base - 1) + "]");
        mesh.tets[t][k] = static_cast<int>(v - base);
      }
      for (size_t a = 1 + npt; a < per; ++a) (void)parse_double(tok[a], L.where(), "attribute");
      tline[t] = L.line();
    }
    if (L.next(tok)) throw Error(L.where() + ": more tetrahedra than the " + std::to_string(nt) + " declared in the header");
    if (npt == 10 && report) report->notes.push_back("10-node tetrahedra: only the 4 corners are used");
  }
  if (report) report->format = "tetgen";
  finish_tet_mesh(mesh, node_path, vline, ele_path, tline, report);
  return mesh;
}

}  // namespace xb
