// medit .mesh.
#include "mesh_io.hpp"
#include "text_lines.hpp"

#include <algorithm>
#include <cctype>
#include <map>

namespace xb {

using namespace mesh_text;

namespace {
// The next value of entry i (0-based) of a section of n; a keyword there means the section ended
// early: the count is larger than the data (numbers never start with a letter, but nan and inf).
std::string_view entry_token(Lines& L, const std::string& what, const char* section, long long i, long long n) {
  const std::string_view t = L.require_token(what);
  std::string low(t);
  for (auto& c : low) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (std::isalpha(static_cast<unsigned char>(t[0])) && low != "nan" && low != "inf" && low != "infinity")
    throw Error(L.where() + ": " + section + " declares " + std::to_string(n) + " entries, but the section ends after " +
                std::to_string(i) + " (at '" + std::string(t) + "'): the count is larger than the data");
  return t;
}

// The Vertices section after its keyword: count, then x y z ref per vertex. Returns the count.
long long read_vertices(Lines& L, size_t bytes, TetMesh& mesh, std::vector<int>& vline) {
  const long long nv = parse_count(L.require_token("the number of vertices"), L.where(), "number of vertices", bytes);
  mesh.vertices.resize(3, nv);
  vline.resize(nv);
  for (long long i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c)
      mesh.vertices(c, i) = parse_double(entry_token(L, "vertex " + std::to_string(i + 1) + " of " + std::to_string(nv), "Vertices", i, nv),
                                         L.where(), "coordinate");
    vline[i] = L.line();
    (void)parse_int(L.require_token("a vertex reference"), L.where(), "vertex reference");
  }
  return nv;
}

// The Tetrahedra section after its keyword: count, then 4 one-based vertex indices and a ref.
void read_tetrahedra(Lines& L, size_t bytes, long long nv, TetMesh& mesh, std::vector<int>& tline) {
  const long long nt = parse_count(L.require_token("the number of tetrahedra"), L.where(), "number of tetrahedra", bytes);
  mesh.tets.resize(nt);
  tline.resize(nt);
  for (long long t = 0; t < nt; ++t) {
    for (int k = 0; k < 4; ++k) {
      const long long v = parse_int(entry_token(L, "tetrahedron " + std::to_string(t + 1) + " of " + std::to_string(nt), "Tetrahedra", t, nt),
                                    L.where(), "vertex index");
      if (v < 1 || v > nv)
        throw Error(L.where() + ": vertex index " + std::to_string(v) + " out of range [1, " + std::to_string(nv) + "]");
      mesh.tets[t][k] = static_cast<int>(v - 1);
    }
    tline[t] = L.line();
    (void)parse_int(L.require_token("a tetrahedron reference"), L.where(), "tetrahedron reference");
  }
}
}  // namespace

TetMesh read_medit(const std::string& path, MeshReadReport* report) {
  Lines L(path, true);
  const size_t bytes = file_size(path);
  // Entries per item of the sections we skip.
  static const std::map<std::string, int, std::less<>> skip = {
      {"Edges", 3},          {"Triangles", 4}, {"Quadrilaterals", 5}, {"Hexahedra", 9},  {"Prisms", 7},
      {"Corners", 1},        {"Ridges", 1},    {"RequiredVertices", 1}, {"RequiredEdges", 1},
      {"RequiredTriangles", 1}, {"Normals", 3}, {"NormalAtVertices", 2}, {"Tangents", 3}, {"TangentAtEdges", 2},
      {"Identifier", 0}};
  TetMesh mesh;
  std::vector<int> vline, tline;
  bool have_v = false, have_t = false, ended = false;
  long long nv = 0;
  std::string_view tok;
  bool first = true;
  while (!ended && L.next_token(tok)) {
    const int kw_line = L.line();
    if (first && tok != "MeshVersionFormatted")
      throw Error(L.where() + ": expected 'MeshVersionFormatted' (not a medit .mesh file?), found '" + std::string(tok) + "'");
    first = false;
    if (tok == "MeshVersionFormatted") {
      const long long v = parse_int(L.require_token("the version"), L.where(), "version");
      if (v != 1 && v != 2) throw Error(L.where() + ": MeshVersionFormatted " + std::to_string(v) + " is not supported (1 or 2)");
    } else if (tok == "Dimension") {
      const long long d = parse_int(L.require_token("the dimension"), L.where(), "dimension");
      if (d != 3) throw Error(L.where() + ": Dimension " + std::to_string(d) + " (only 3-D meshes are read)");
    } else if (tok == "Vertices") {
      if (have_v) throw Error(L.where() + ": a second Vertices section");
      have_v = true;
      nv = read_vertices(L, bytes, mesh, vline);
    } else if (tok == "Tetrahedra") {
      if (have_t) throw Error(L.where() + ": a second Tetrahedra section");
      if (!have_v) throw Error(L.where() + ": Tetrahedra before Vertices");
      have_t = true;
      read_tetrahedra(L, bytes, nv, mesh, tline);
    } else if (tok == "End") {
      ended = true;
    } else if (auto it = skip.find(tok); it != skip.end()) {
      if (it->second == 0) {
        (void)L.require_token("the identifier");
        continue;
      }
      const long long n = parse_count(L.require_token("the number of " + std::string(tok)), L.where(), "count", bytes);
      for (long long i = 0; i < n * it->second; ++i)
        (void)parse_double(L.require_token(std::string(tok) + " entries"), L.where(), std::string(tok) + " entry");
      if (report) report->notes.push_back("ignored " + std::to_string(n) + " " + std::string(tok));
    } else {
      const std::string s(tok);
      const bool numeric = !s.empty() && (std::isdigit(static_cast<unsigned char>(s[0])) || s[0] == '-' || s[0] == '+' || s[0] == '.');
      throw Error(L.where(kw_line) + (numeric ? ": unexpected number '" + s + "' (more entries than the section's count?)"
                                               : ": unknown medit keyword '" + s + "'"));
    }
  }
  if (first) throw Error(path + ": empty file");
  if (!have_v) throw Error(path + ": no Vertices section");
  if (!have_t) throw Error(path + ": no Tetrahedra section");
  if (report) report->format = "medit";
  finish_tet_mesh(mesh, path, vline, path, tline, report);
  return mesh;
}

}  // namespace xb
