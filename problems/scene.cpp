#include "scene.hpp"

#include "error.hpp"
#include "generators.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#ifndef XB_SOURCE_DIR
#define XB_SOURCE_DIR "."
#endif

namespace fs = std::filesystem;

namespace xb {

std::string scene_dir() {
  if (const char* d = std::getenv("XB_SCENE_DIR")) return d;
  return std::string(XB_SOURCE_DIR) + "/problems/scenes";
}

std::vector<std::string> scene_names() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(scene_dir(), ec))
    if (e.path().extension() == ".toml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string resolve_scene(const std::string& name_or_file) {
  if (name_or_file.find('/') != std::string::npos || name_or_file.ends_with(".toml")) {
    if (!fs::is_regular_file(name_or_file)) throw Error("scene file '" + name_or_file + "' does not exist");
    return name_or_file;
  }
  const auto names = scene_names();
  if (std::find(names.begin(), names.end(), name_or_file) == names.end()) {
    std::string valid;
    for (const auto& n : names) valid += (valid.empty() ? "" : ", ") + n;
    throw Error("unknown scene '" + name_or_file + "' (valid: " + valid + ")");
  }
  return scene_dir() + "/" + name_or_file + ".toml";
}

namespace {
std::string node_text(const toml::node& n, const std::string& where) {
  if (auto s = n.as_string()) return s->get();
  if (auto i = n.as_integer()) return std::to_string(i->get());
  if (auto d = n.as_floating_point()) {
    std::ostringstream os;
    os.precision(17);
    os << d->get();
    return os.str();
  }
  if (auto b = n.as_boolean()) return b->get() ? "1" : "0";
  throw Error(where + ": unsupported value type (use a number or a string)");
}

void flatten(const toml::table& t, const std::string& prefix, const std::string& path, std::vector<TomlEntry>& out) {
  for (const auto& [k, v] : t) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    const int line = static_cast<int>(v.source().begin.line);
    const std::string where = path + ":" + std::to_string(line);
    if (auto sub = v.as_table()) {
      flatten(*sub, key, path, out);
    } else if (auto arr = v.as_array()) {
      TomlEntry e{key, "", line, true, {}};
      for (const auto& item : *arr) e.items.push_back(node_text(item, where + ": '" + key + "'"));
      out.push_back(e);
    } else {
      out.push_back({key, node_text(v, where + ": '" + key + "'"), line, false, {}});
    }
  }
}
}  // namespace

std::vector<TomlEntry> read_toml_flat(const std::string& path) {
  if (!fs::is_regular_file(path)) throw Error(path + ": no such file");
  toml::table t;
  try {
    t = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": malformed TOML: " << e.description();
    throw Error(os.str());
  }
  std::vector<TomlEntry> out;
  flatten(t, "", path, out);
  std::sort(out.begin(), out.end(), [](const TomlEntry& a, const TomlEntry& b) { return a.line < b.line; });
  return out;
}

void load_scene_file(const std::string& path, Params& p) {
  for (const auto& e : read_toml_flat(path)) {
    const std::string where = path + ":" + std::to_string(e.line);
    if (e.is_array) throw Error(where + ": '" + e.key + "' must be a single value, not a list");
    set_param(p, e.key, e.value, where);
  }
}

Problem make_tet_problem(const std::string& name, const TetMesh& mesh, const Params& p) {
  Problem prob;
  prob.name = name;
  const int n = static_cast<int>(mesh.vertices.cols());
  prob.particles.x = mesh.vertices;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, n);
  prob.particles.w = Eigen::VectorXd::Constant(n, 1.0 / p.particle_mass);
  auto& T = prob.tets;
  T.idx = mesh.tets;
  T.Dm_inv.resize(mesh.tets.size());
  T.rest_volume.resize(mesh.tets.size());
  T.compliance.resize(mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const auto& e = mesh.tets[t];
    Eigen::Matrix3d Dm;
    for (int c = 0; c < 3; ++c) Dm.col(c) = mesh.vertices.col(e[c + 1]) - mesh.vertices.col(e[0]);
    const double V = Dm.determinant() / 6.0;
    if (!(V > 0)) throw Error(name + ": tet " + std::to_string(t) + " has non-positive rest volume");
    T.Dm_inv[t] = Dm.inverse();
    T.rest_volume[t] = V;
    T.compliance[t] = 1.0 / (p.stiffness * V);
  }
  prob.surface = boundary_faces(mesh);
  prob.gravity = Eigen::Vector3d(0, p.gravity, 0);
  return prob;
}

Problem make_cloth_problem(const std::string& name, const TriMesh& mesh, const Params& p) {
  Problem prob;
  prob.name = name;
  const int n = static_cast<int>(mesh.vertices.cols());
  prob.particles.x = mesh.vertices;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, n);
  prob.particles.w = Eigen::VectorXd::Constant(n, 1.0 / p.particle_mass);
  auto& D = prob.distance;
  D.idx = mesh.edges;
  for (const auto& e : mesh.edges) {
    D.rest_length.push_back((mesh.vertices.col(e[0]) - mesh.vertices.col(e[1])).norm());
    D.compliance.push_back(p.compliance);
  }
  prob.surface = mesh.triangles;
  prob.gravity = Eigen::Vector3d(0, p.gravity, 0);
  return prob;
}

namespace {

// The paper's Fig. 8: a horizontal N×N cloth at y = 0.5 under gravity, pinned at vertices N
// and NV−1 as in the authors' code: the two corners (i = 0, k = N) and (i = N, k = N).
Problem build_cloth_hang(const Params& p) {
  const int N = p.resolution;
  const TriMesh m = make_cloth_grid(N, p.size, 0.5);
  Problem prob = make_cloth_problem("cloth_hang", m, p);
  prob.particles.w[N] = 0;                    // vertex (i = 0, k = N)
  prob.particles.w[(N + 1) * (N + 1) - 1] = 0;  // vertex (i = N, k = N)
  return prob;
}

// A cantilever: a bar of (aspect·r)×r×r cubes along x, its x = 0 end pinned, under gravity.
Problem build_bar_hang(const Params& p) {
  const int r = p.resolution;
  const double h = p.size / r;
  const TetMesh m = make_tet_bar(p.aspect * r, r, r, h);
  Problem prob = make_tet_problem("bar_hang", m, p);
  for (int i = 0; i < prob.particles.size(); ++i) {
    if (m.vertices(0, i) == 0.0) prob.particles.w[i] = 0;
    prob.particles.x(0, i) *= p.prestretch;
  }
  return prob;
}

}  // namespace

const std::vector<BuilderInfo>& scene_builders() {
  static const std::vector<BuilderInfo> b = {
      {"cloth_hang", "horizontal cloth, two corners pinned, gravity (paper Fig. 8)", build_cloth_hang},
      {"bar_hang", "tet bar with one end pinned under gravity (a cantilever)", build_bar_hang},
  };
  return b;
}

Problem build_problem(const Params& p) {
  validate(p);
  for (const auto& b : scene_builders())
    if (b.name == p.scene) {
      Problem prob = b.build(p);
      prob.check();
      return prob;
    }
  std::string valid;
  for (const auto& b : scene_builders()) valid += (valid.empty() ? "" : ", ") + b.name;
  throw Error("unknown scene builder '" + p.scene + "' (valid: " + valid + ")");
}

}  // namespace xb
