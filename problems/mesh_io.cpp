#include "mesh_io.hpp"

#include "error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string_view>
#include <unordered_map>

namespace fs = std::filesystem;

namespace xb {

namespace {

std::string read_whole(const std::string& path) {
  if (!fs::is_regular_file(path)) throw Error(path + ": no such mesh file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Line-oriented reading with line numbers; '#' starts a comment when `comments` is set.
class Lines {
 public:
  Lines(std::string path, bool comments) : path_(std::move(path)), text_(read_whole(path_)), comments_(comments) {
    if (text_.find('\0') != std::string::npos)
      throw Error(path_ + ": contains NUL bytes (a binary file? only ASCII meshes are read)");
  }
  const std::string& path() const { return path_; }
  // Nothing but whitespace after the current line.
  bool at_end() const { return text_.find_first_not_of(" \t\r\n\v\f", pos_) == std::string::npos; }
  int line() const { return line_; }
  std::string where() const { return path_ + ":" + std::to_string(line_); }
  std::string where(int line) const { return path_ + ":" + std::to_string(line); }

  // The tokens of the next line that has any (blank and comment-only lines are skipped).
  // Returns false at the end of the file.
  bool next(std::vector<std::string_view>& tokens) {
    tokens.clear();
    while (pos_ < text_.size()) {
      size_t end = text_.find('\n', pos_);
      if (end == std::string::npos) end = text_.size();
      std::string_view l(text_.data() + pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      if (comments_) {
        const size_t h = l.find('#');
        if (h != std::string_view::npos) l = l.substr(0, h);
      }
      size_t i = 0;
      while (i < l.size()) {
        while (i < l.size() && is_space(l[i])) ++i;
        size_t j = i;
        while (j < l.size() && !is_space(l[j])) ++j;
        if (j > i) tokens.push_back(l.substr(i, j - i));
        i = j;
      }
      if (!tokens.empty()) return true;
    }
    return false;
  }
  // As next(), but the end of the file is an error: "truncated while reading <what>".
  void require(std::vector<std::string_view>& tokens, const std::string& what) {
    if (!next(tokens)) throw Error(where() + ": file ends early (truncated?) while reading " + what);
  }
  // A single token stream across lines (medit), with the line of the last token.
  bool next_token(std::string_view& tok) {
    while (tok_i_ >= tok_buf_.size()) {
      if (!next(tok_buf_)) return false;
      tok_i_ = 0;
    }
    tok = tok_buf_[tok_i_++];
    return true;
  }
  std::string_view require_token(const std::string& what) {
    std::string_view t;
    if (!next_token(t)) throw Error(where() + ": file ends early (truncated?) while reading " + what);
    return t;
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
  std::string path_, text_;
  bool comments_;
  size_t pos_ = 0;
  int line_ = 0;
  std::vector<std::string_view> tok_buf_;
  size_t tok_i_ = 0;
};

long long parse_int(std::string_view t, const std::string& where, const std::string& what) {
  long long v = 0;
  const char* b = t.data();
  const char* e = t.data() + t.size();
  if (!t.empty() && *b == '+') ++b;
  auto [p, ec] = std::from_chars(b, e, v);
  if (ec != std::errc() || p != e)
    throw Error(where + ": " + what + " '" + std::string(t) + "' is not an integer");
  return v;
}

double parse_double(std::string_view t, const std::string& where, const std::string& what) {
  const std::string s(t);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size()) throw Error(where + ": " + what + " '" + s + "' is not a number");
  if (!std::isfinite(v)) throw Error(where + ": " + what + " '" + s + "' is not a finite number");
  return v;
}

// A declared count: non-negative and not larger than the file could hold (so a corrupt count
// cannot trigger a huge allocation).
long long parse_count(std::string_view t, const std::string& where, const std::string& what, size_t file_bytes) {
  const long long n = parse_int(t, where, what);
  if (n < 0) throw Error(where + ": " + what + " " + std::to_string(n) + " is negative");
  if (static_cast<unsigned long long>(n) > file_bytes / 2 + 1)
    throw Error(where + ": " + what + " " + std::to_string(n) + " is more than the file can hold (wrong count?)");
  return n;
}

void expect_tokens(const Lines& L, const std::vector<std::string_view>& tok, size_t n, const std::string& what) {
  if (tok.size() != n)
    throw Error(L.where() + ": " + what + ": expected " + std::to_string(n) + " values, found " + std::to_string(tok.size()) +
                (L.at_end() && tok.size() < n ? " (the file ends here: truncated?)" : ""));
}

size_t file_size(const std::string& path) {
  std::error_code ec;
  const auto s = fs::file_size(path, ec);
  return ec ? 0 : static_cast<size_t>(s);
}

}  // namespace

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

// ---------------------------------------------------------------- TetGen
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

// ---------------------------------------------------------------- gmsh
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

TetMesh read_gmsh(const std::string& path, MeshReadReport* report) {
  Lines L(path, false);
  const size_t bytes = file_size(path);
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

  auto add_node = [&](long long tag, const std::vector<std::string_view>& t, size_t first) {
    if (!node_index.emplace(tag, static_cast<int>(vline.size())).second)
      throw Error(L.where() + ": node tag " + std::to_string(tag) + " appears twice");
    for (int c = 0; c < 3; ++c) xyz.push_back(parse_double(t[first + c], L.where(), "coordinate"));
    vline.push_back(L.line());
  };
  auto add_element = [&](long long type, const std::vector<std::string_view>& t, size_t first) {
    if (type == 4 || type == 11) {
      std::array<long long, 4> e;
      for (int k = 0; k < 4; ++k) e[k] = parse_int(t[first + k], L.where(), "node tag");
      tet_tags.push_back(e);
      tline.push_back(L.line());
      if (type == 11) ++tets10;
    } else {
      ++ignored[type];
    }
  };

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
      if (version == "4.1") {
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
      } else {
        L.require(tok, "the number of nodes");
        expect_tokens(L, tok, 1, "number of nodes");
        const long long n = parse_count(tok[0], L.where(), "number of nodes", bytes);
        for (long long i = 0; i < n; ++i) {
          L.require(tok, "node " + std::to_string(i + 1) + " of " + std::to_string(n));
          expect_tokens(L, tok, 4, "node (<tag> <x> <y> <z>)");
          add_node(parse_int(tok[0], L.where(), "node tag"), tok, 1);
        }
      }
      expect_end(L, "Nodes", tok);
    } else if (sec == "$Elements") {
      if (version.empty()) throw Error(L.where() + ": $Elements before $MeshFormat");
      if (have_elements) throw Error(L.where() + ": a second $Elements section");
      have_elements = true;
      if (version == "4.1") {
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
      } else {
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
      expect_end(L, "Elements", tok);
    } else if (sec.size() > 1 && sec[0] == '$' && !sec.starts_with("$End")) {
      skip_section(L, std::string(sec.substr(1)), tok);  // $PhysicalNames, $Entities, $NodeData, …
    } else {
      throw Error(L.where() + ": unexpected '" + std::string(sec) + "' outside a section");
    }
  }
  if (version.empty()) throw Error(path + ": no $MeshFormat section (not a gmsh .msh file?)");
  if (!have_nodes) throw Error(path + ": no $Nodes section");
  if (!have_elements) throw Error(path + ": no $Elements section");

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
    std::cerr << path << ": note: ignored " << n << " " << gmsh_type_name(type) << " (gmsh type " << type
              << "); only tetrahedra are read\n";
  finish_tet_mesh(mesh, path, vline, path, tline, report);
  return mesh;
}

// ---------------------------------------------------------------- medit
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
      nv = parse_count(L.require_token("the number of vertices"), L.where(), "number of vertices", bytes);
      mesh.vertices.resize(3, nv);
      vline.resize(nv);
      for (long long i = 0; i < nv; ++i) {
        for (int c = 0; c < 3; ++c)
          mesh.vertices(c, i) = parse_double(L.require_token("vertex " + std::to_string(i + 1) + " of " + std::to_string(nv)),
                                             L.where(), "coordinate");
        vline[i] = L.line();
        (void)parse_int(L.require_token("a vertex reference"), L.where(), "vertex reference");
      }
    } else if (tok == "Tetrahedra") {
      if (have_t) throw Error(L.where() + ": a second Tetrahedra section");
      if (!have_v) throw Error(L.where() + ": Tetrahedra before Vertices");
      have_t = true;
      const long long nt = parse_count(L.require_token("the number of tetrahedra"), L.where(), "number of tetrahedra", bytes);
      mesh.tets.resize(nt);
      tline.resize(nt);
      for (long long t = 0; t < nt; ++t) {
        for (int k = 0; k < 4; ++k) {
          const long long v = parse_int(L.require_token("tetrahedron " + std::to_string(t + 1) + " of " + std::to_string(nt)),
                                        L.where(), "vertex index");
          if (v < 1 || v > nv)
            throw Error(L.where() + ": vertex index " + std::to_string(v) + " out of range [1, " + std::to_string(nv) + "]");
          mesh.tets[t][k] = static_cast<int>(v - 1);
        }
        tline[t] = L.line();
        (void)parse_int(L.require_token("a tetrahedron reference"), L.where(), "tetrahedron reference");
      }
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

TetMesh read_tet_mesh(const std::string& path, MeshReadReport* report) {
  const fs::path p(path);
  const std::string ext = p.extension().string();
  if (ext == ".node" || ext == ".ele") {
    fs::path node = p, ele = p;
    node.replace_extension(".node");
    ele.replace_extension(".ele");
    if (!fs::is_regular_file(node)) throw Error(path + ": the TetGen pair needs " + node.string() + ", which does not exist");
    if (!fs::is_regular_file(ele)) throw Error(path + ": the TetGen pair needs " + ele.string() + ", which does not exist");
    return read_tetgen(node.string(), ele.string(), report);
  }
  if (ext == ".msh") return read_gmsh(path, report);
  if (ext == ".mesh") return read_medit(path, report);
  throw Error(path + ": unknown mesh format '" + ext + "' (valid: .node/.ele (TetGen), .msh (gmsh 2.2/4.1 ASCII), .mesh (medit))");
}

}  // namespace xb
