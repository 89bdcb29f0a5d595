// gmsh .msh, ASCII 2.2 and 4.1.
#include "mesh_io.hpp"
#include "text_lines.hpp"

#include <algorithm>
#include <iostream>
#include <map>
#include <unordered_map>

namespace xb {

using namespace mesh_text;

namespace {

// Nodes per element for the gmsh element types (1…31); 0 = unknown.
int gmsh_nodes_per_element(long long type) {
  static const int n[] = {0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5, 6, 20, 35, 56};
  return type >= 1 && type <= 31 ? n[type] : 0;
}
const char* gmsh_type_name(long long type) {
  switch (type) {
    case 1: return "lines";
    case 2: return "triangles";
    case 3: return "quadrangles";
    case 4: return "tetrahedra";
    case 5: return "hexahedra";
    case 6: return "prisms";
    case 7: return "pyramids";
    case 11: return "10-node tetrahedra";
    case 15: return "points";
    default: return "elements";
  }
}

// Skips to the line "$End<name>".
void skip_section(Lines& L, const std::string& name, std::vector<std::string_view>& tok) {
  const int start = L.line();
  const std::string end = "$End" + name;
  while (L.next(tok))
    if (tok[0] == end) return;
  throw Error(L.where(start) + ": section $" + name + " has no " + end + " (truncated?)");
}

void expect_end(Lines& L, const std::string& name, std::vector<std::string_view>& tok) {
  L.require(tok, "$End" + name);
  if (tok.size() != 1 || tok[0] != "$End" + name)
    throw Error(L.where() + ": expected $End" + name + " (more entries than declared?), found '" + std::string(tok[0]) + "'");
}

}  // namespace

namespace {
// One .msh file read section by section; tets keep their node tags until every node is known.
class GmshReader {
 public:
  GmshReader(const std::string& path) : path_(path), L(path, false), bytes(file_size(path)) {}
  TetMesh read(MeshReadReport* report);

 private:
  void read_sections();
  void read_nodes_41();
  void read_nodes_22();
  void read_elements_41();
  void read_elements_22();
  TetMesh build_mesh(MeshReadReport* report) const;

  void add_node(long long tag, const std::vector<std::string_view>& t, size_t first) {
    if (!node_index.emplace(tag, static_cast<int>(vline.size())).second)
      throw Error(L.where() + ": node tag " + std::to_string(tag) + " appears twice");
    for (int c = 0; c < 3; ++c) xyz.push_back(parse_double(t[first + c], L.where(), "coordinate"));
    vline.push_back(L.line());
  }
  void add_element(long long type, const std::vector<std::string_view>& t, size_t first) {
    if (type == 4 || type == 11) {
      std::array<long long, 4> e;
      for (int k = 0; k < 4; ++k) e[k] = parse_int(t[first + k], L.where(), "node tag");
      tet_tags.push_back(e);
      tline.push_back(L.line());
      if (type == 11) ++tets10;
    } else {
      ++ignored[type];
    }
  }

  std::string path_;
  Lines L;
  size_t bytes;
  std::vector<std::string_view> tok;
  std::string version;
  bool have_nodes = false, have_elements = false;
  std::unordered_map<long long, int> node_index;  // gmsh node tag → vertex index
  std::vector<double> xyz;
  std::vector<int> vline;
  std::vector<std::array<long long, 4>> tet_tags;
  std::vector<int> tline;
  std::map<long long, long long> ignored;  // element type → count
  long long tets10 = 0;
};

void GmshReader::read_sections() {
  while (L.next(tok)) {
    const std::string_view sec = tok[0];
    if (sec == "$MeshFormat") {
      L.require(tok, "the $MeshFormat line (<version> <file-type> <data-size>)");
      if (tok.size() != 3) throw Error(L.where() + ": $MeshFormat: expected <version> <file-type> <data-size>");
      version = std::string(tok[0]);
      if (version != "2.2" && version != "4.1" && version != "2" && version != "2.0" && version != "2.1")
        throw Error(L.where() + ": gmsh format version " + version + " is not supported (2.2 or 4.1 ASCII)");
      if (tok[1] != "0") throw Error(L.where() + ": binary .msh is not supported (save as ASCII: gmsh -format msh22 or msh41)");
      expect_end(L, "MeshFormat", tok);
    } else if (sec == "$Nodes") {
      if (version.empty()) throw Error(L.where() + ": $Nodes before $MeshFormat");
      if (have_nodes) throw Error(L.where() + ": a second $Nodes section");
      have_nodes = true;
      version == "4.1" ? read_nodes_41() : read_nodes_22();
      expect_end(L, "Nodes", tok);
    } else if (sec == "$Elements") {
      if (version.empty()) throw Error(L.where() + ": $Elements before $MeshFormat");
      if (have_elements) throw Error(L.where() + ": a second $Elements section");
      have_elements = true;
      version == "4.1" ? read_elements_41() : read_elements_22();
      expect_end(L, "Elements", tok);
    } else if (sec.size() > 1 && sec[0] == '$' && !sec.starts_with("$End")) {
      skip_section(L, std::string(sec.substr(1)), tok);  // $PhysicalNames, $Entities, $NodeData, …
    } else {
      throw Error(L.where() + ": unexpected '" + std::string(sec) + "' outside a section");
    }
  }
  if (version.empty()) throw Error(path_ + ": no $MeshFormat section (not a gmsh .msh file?)");
  if (!have_nodes) throw Error(path_ + ": no $Nodes section");
  if (!have_elements) throw Error(path_ + ": no $Elements section");
}

void GmshReader::read_nodes_41() {
  L.require(tok, "the $Nodes header");
  expect_tokens(L, tok, 4, "$Nodes header (<#blocks> <#nodes> <min tag> <max tag>)");
  const long long nblocks = parse_count(tok[0], L.where(), "number of node blocks", bytes);
  const long long nnodes = parse_count(tok[1], L.where(), "number of nodes", bytes);
  long long seen = 0;
  std::vector<long long> tags;
  for (long long b = 0; b < nblocks; ++b) {
    L.require(tok, "node block " + std::to_string(b + 1) + " of " + std::to_string(nblocks));
    expect_tokens(L, tok, 4, "node block header (<dim> <tag> <parametric> <#nodes>)");
    const long long dim = parse_int(tok[0], L.where(), "entity dimension");
    const long long parametric = parse_int(tok[2], L.where(), "parametric flag");
    const long long n = parse_count(tok[3], L.where(), "number of nodes in block", bytes);
    if (parametric != 0 && parametric != 1) throw Error(L.where() + ": parametric flag must be 0 or 1");
    if (seen + n > nnodes)
      throw Error(L.where() + ": node blocks hold more than the " + std::to_string(nnodes) + " nodes declared");
    tags.resize(n);
    for (long long i = 0; i < n; ++i) {
      L.require(tok, "a node tag");
      expect_tokens(L, tok, 1, "node tag");
      tags[i] = parse_int(tok[0], L.where(), "node tag");
    }
    const size_t per = 3 + (parametric ? std::max<long long>(dim, 0) : 0);
    for (long long i = 0; i < n; ++i) {
      L.require(tok, "node coordinates");
      expect_tokens(L, tok, per, "node coordinates");
      add_node(tags[i], tok, 0);
    }
    seen += n;
  }
  if (seen != nnodes)
    throw Error(L.where() + ": node blocks hold " + std::to_string(seen) + " nodes, the header declares " +
                std::to_string(nnodes));
}

void GmshReader::read_nodes_22() {
  L.require(tok, "the number of nodes");
  expect_tokens(L, tok, 1, "number of nodes");
  const long long n = parse_count(tok[0], L.where(), "number of nodes", bytes);
  for (long long i = 0; i < n; ++i) {
    L.require(tok, "node " + std::to_string(i + 1) + " of " + std::to_string(n));
    expect_tokens(L, tok, 4, "node (<tag> <x> <y> <z>)");
    add_node(parse_int(tok[0], L.where(), "node tag"), tok, 1);
  }
}

void GmshReader::read_elements_41() {
  L.require(tok, "the $Elements header");
  expect_tokens(L, tok, 4, "$Elements header (<#blocks> <#elements> <min tag> <max tag>)");
  const long long nblocks = parse_count(tok[0], L.where(), "number of element blocks", bytes);
  const long long nelem = parse_count(tok[1], L.where(), "number of elements", bytes);
  long long seen = 0;
  for (long long b = 0; b < nblocks; ++b) {
    L.require(tok, "element block " + std::to_string(b + 1) + " of " + std::to_string(nblocks));
    expect_tokens(L, tok, 4, "element block header (<dim> <tag> <type> <#elements>)");
    const long long type = parse_int(tok[2], L.where(), "element type");
    const long long n = parse_count(tok[3], L.where(), "number of elements in block", bytes);
    const int npe = gmsh_nodes_per_element(type);
    if (npe == 0) throw Error(L.where() + ": unknown gmsh element type " + std::to_string(type));
    if (seen + n > nelem)
      throw Error(L.where() + ": element blocks hold more than the " + std::to_string(nelem) + " elements declared");
    for (long long i = 0; i < n; ++i) {
      L.require(tok, "an element");
      expect_tokens(L, tok, 1 + npe, std::string("element of type ") + std::to_string(type) + " (<tag> <nodes>)");
      (void)parse_int(tok[0], L.where(), "element tag");
      add_element(type, tok, 1);
    }
    seen += n;
  }
  if (seen != nelem)
    throw Error(L.where() + ": element blocks hold " + std::to_string(seen) + " elements, the header declares " +
                std::to_string(nelem));
}

void GmshReader::read_elements_22() {
  L.require(tok, "the number of elements");
  expect_tokens(L, tok, 1, "number of elements");
  const long long n = parse_count(tok[0], L.where(), "number of elements", bytes);
  for (long long i = 0; i < n; ++i) {
    L.require(tok, "element " + std::to_string(i + 1) + " of " + std::to_string(n));
    if (tok.size() < 3) throw Error(L.where() + ": element: expected <tag> <type> <#tags> <tags> <nodes>");
    const long long type = parse_int(tok[1], L.where(), "element type");
    const long long ntags = parse_int(tok[2], L.where(), "number of tags");
    const int npe = gmsh_nodes_per_element(type);
    if (npe == 0) throw Error(L.where() + ": unknown gmsh element type " + std::to_string(type));
    if (ntags < 0 || ntags > 64) throw Error(L.where() + ": number of tags " + std::to_string(ntags) + " is implausible");
    expect_tokens(L, tok, 3 + ntags + npe, std::string("element of type ") + std::to_string(type));
    add_element(type, tok, 3 + ntags);
  }
}

TetMesh GmshReader::build_mesh(MeshReadReport* report) const {
  TetMesh mesh;
  const long long nv = static_cast<long long>(vline.size());
  mesh.vertices = Eigen::Map<const Eigen::Matrix3Xd>(xyz.data(), 3, nv);
  mesh.tets.resize(tet_tags.size());
  for (size_t t = 0; t < tet_tags.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      auto it = node_index.find(tet_tags[t][k]);
      if (it == node_index.end())
        throw Error(L.where(tline[t]) + ": tetrahedron refers to node tag " + std::to_string(tet_tags[t][k]) +
                    ", which no $Nodes entry defines");
      mesh.tets[t][k] = it->second;
    }
  if (report) {
    report->format = "gmsh " + (version == "4.1" ? version : std::string("2.2"));
    for (const auto& [type, n] : ignored)
      report->notes.push_back("ignored " + std::to_string(n) + " " + gmsh_type_name(type) + " (type " + std::to_string(type) + ")");
    if (tets10) report->notes.push_back("10-node tetrahedra: only the 4 corners are used");
  }
  for (const auto& [type, n] : ignored)
    std::cerr << path_ << ": note: ignored " << n << " " << gmsh_type_name(type) << " (gmsh type " << type
              << "); only tetrahedra are read\n";
  return mesh;
}

TetMesh GmshReader::read(MeshReadReport* report) {
  read_sections();
  TetMesh mesh = build_mesh(report);
  finish_tet_mesh(mesh, path_, vline, path_, tline, report);
  return mesh;
}
}  // namespace

TetMesh read_gmsh(const std::string& path, MeshReadReport* report) { return GmshReader(path).read(report); }

}  // namespace xb
