#include "scene.hpp"

#include "../core/error.hpp"
#include "scene_pins.hpp"
#include "toml_catalogue.hpp"
#include "meshes/generators.hpp"
#include "meshes/real_meshes.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace xb {

namespace {
const TomlCatalogue scenes{"scene", "scenes", "XB_SCENE_DIR"};
}  // namespace

std::string scene_dir() { return scenes.dir(); }
std::vector<std::string> scene_names() { return scenes.names(); }
std::string resolve_scene(const std::string& name_or_file) { return scenes.resolve(name_or_file); }

Problem make_tet_problem(const std::string& name, const TetMesh& mesh, const SceneSettings& p) {
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

Problem make_cloth_problem(const std::string& name, const TriMesh& mesh, const SceneSettings& p) {
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
Problem build_cloth_hang(const SceneSettings& p) {
  const int N = p.resolution;
  TriMesh m = make_cloth_grid(N, p.size, 0.5);
  if (p.variant == "near_degenerate") flatten_some_triangles(m);
  Problem prob = make_cloth_problem("cloth_hang", m, p);
  prob.particles.w[N] = 0;                    // vertex (i = 0, k = N)
  prob.particles.w[(N + 1) * (N + 1) - 1] = 0;  // vertex (i = N, k = N)
  return prob;
}

// A cantilever: a bar of (aspect·r)×r×r cubes along x, its x = 0 end pinned, under gravity.
Problem build_bar_hang(const SceneSettings& p) {
  const int r = p.resolution;
  const double h = p.size / r;
  TetMesh m = make_tet_bar(p.aspect * r, r, r, h);
  if (p.variant == "near_degenerate") flatten_some_tets(m);
  Problem prob = make_tet_problem("bar_hang", m, p);
  for (int i = 0; i < prob.particles.size(); ++i) {
    if (m.vertices(0, i) == 0.0) prob.particles.w[i] = 0;
    prob.particles.x(0, i) *= p.prestretch;
  }
  return prob;
}

// ---- The paper's scenes. Each takes its mesh from the `mesh` key (load_tet_mesh).

// Uniform scaling about the origin so that the y extent is `height` m: the rest shape (volumes,
// hence α = 1/(μV)) scales with it, as when the authors load their 0.2 m bunny.
void scale_to_height(TetMesh& m, double height) {
  const double extent = m.vertices.row(1).maxCoeff() - m.vertices.row(1).minCoeff();
  if (!(extent > 0)) throw Error("parameter 'mesh_height': the mesh has no y extent to scale");
  m.vertices *= height / extent;
}

Problem tet_scene(const std::string& name, const SceneSettings& p, const std::string& fallback_mesh, TetMesh* mesh_out = nullptr) {
  MeshReadReport report;
  TetMesh m = load_tet_mesh(p.mesh, p, fallback_mesh, &report);
  if (p.mesh_height > 0) scale_to_height(m, p.mesh_height);
  if (p.variant == "near_degenerate") flatten_some_tets(m);
  Problem prob = make_tet_problem(name, m, p);
  if (mesh_out) *mesh_out = std::move(m);
  return prob;
}

// Figs. 13/17: every vertex collapsed to the minimum y of the mesh, released; no gravity.
// The rest shape is the mesh itself, so every tet starts flat (σ₃ = 0, C = 1).
// init = enlarge instead starts from the rest mesh scaled ×1.5 about its centroid (the authors'
// `enlarge` reinit of the same scene; their near-kernel table is its first solve).
Problem build_squash(const SceneSettings& p) {
  Problem prob = tet_scene("squash", p, "ball");
  Eigen::Matrix3Xd& x = prob.particles.x;
  if (p.init == "enlarge") {
    const Eigen::Vector3d c = x.rowwise().mean();
    x = ((x.colwise() - c) * 1.5).colwise() + c;
    return prob;
  }
  const double ymin = x.row(1).minCoeff();
  x.row(1).setConstant(ymin);
  return prob;
}

// A bar (aspect·r × r × r cubes) twisted about its long (x) axis by `twist` rad end to end,
// released with no gravity.
Problem build_twist_bar(const SceneSettings& p) {
  Problem prob = tet_scene("twist_bar", p, "bar");
  Eigen::Matrix3Xd& x = prob.particles.x;
  const double x0 = x.row(0).minCoeff(), len = x.row(0).maxCoeff() - x0;
  const double yc = (x.row(1).minCoeff() + x.row(1).maxCoeff()) / 2, zc = (x.row(2).minCoeff() + x.row(2).maxCoeff()) / 2;
  for (int i = 0; i < prob.particles.size(); ++i) {
    const double a = p.twist * (len > 0 ? (x(0, i) - x0) / len : 0);
    const double y = x(1, i) - yc, z = x(2, i) - zc;
    x(1, i) = yc + std::cos(a) * y - std::sin(a) * z;
    x(2, i) = zc + std::sin(a) * y + std::cos(a) * z;
  }
  return prob;
}

// The authors' `reinit=beam`: a bar with its left 1% (by x extent, at least the x = min face)
// fixed, under gravity.
Problem build_cantilever(const SceneSettings& p) {
  Problem prob = tet_scene("cantilever", p, "bar");
  const Eigen::Matrix3Xd& x = prob.particles.x;
  const double x0 = x.row(0).minCoeff(), len = x.row(0).maxCoeff() - x0;
  for (int i = 0; i < prob.particles.size(); ++i)
    if (x(0, i) <= x0 + 0.01 * len) prob.particles.w[i] = 0;
  return prob;
}

// A tet ball resting 1 cm above the ground plane y = 0 (the only scene with a collider), falling
// under gravity; particles below the plane are projected onto it, as the paper does.
Problem build_ball_drop(const SceneSettings& p) {
  Problem prob = tet_scene("ball_drop", p, "ball");
  Eigen::Matrix3Xd& x = prob.particles.x;
  const double lift = 0.01 - x.row(1).minCoeff();
  x.row(1).array() += lift;
  prob.planes.push_back(PlaneCollider{0.0});
  return prob;
}

// A chain of `resolution` links of total length `size` along x, its first particle pinned,
// released horizontally under gravity. Particle masses grow with index as i² up to mass_ratio
// (build_problem grades them; the authors' cloth3d setup_num=2 tests this).
Problem build_mass_chain(const SceneSettings& p) {
  const int n = p.resolution + 1;
  TriMesh m;
  m.vertices.resize(3, n);
  for (int i = 0; i < n; ++i) m.vertices.col(i) = Eigen::Vector3d(p.size * i / (n - 1), 0.5, 0);
  if (p.variant == "near_degenerate")  // every 10th link nearly zero length: link lengths span 1e3
    for (int i = 5; i + 1 < n; i += 10) m.vertices.col(i) = m.vertices.col(i + 1) - Eigen::Vector3d(1e-3 * p.size / (n - 1), 0, 0);
  for (int i = 0; i + 1 < n; ++i) m.edges.push_back({i, i + 1});
  Problem prob = make_cloth_problem("mass_chain", m, p);
  prob.particles.w[0] = 0;
  return prob;
}


// A chain of `resolution` links of total length `size` hanging from a pinned particle at the
// origin, straight, at `angle` rad from the downward vertical (in the x-y plane), its last
// particle mass_ratio times as heavy as the others (Tournier et al. 2015's heavy-mass chains).
// Link compliance `compliance` (0 = rigid; variant mu1e12 makes it 1e-12 m/N, the stiffness
// 1e12 of the tet scenes); near_degenerate makes every 10th link (from the 6th) 1e-3 as long.
Problem build_end_mass_chain(const std::string& name, const SceneSettings& p) {
  const int n = p.resolution + 1;
  TriMesh m;
  m.vertices.resize(3, n);
  const Eigen::Vector3d dir(std::sin(p.angle), -std::cos(p.angle), 0);
  std::vector<double> len(p.resolution, p.size / p.resolution);
  if (p.variant == "near_degenerate") {
    if (p.resolution < 6) throw Error("variant near_degenerate shortens every 10th link from the 6th: " + name + " needs resolution >= 6");
    for (int i = 5; i < p.resolution; i += 10) len[i] *= 1e-3;
  }
  m.vertices.col(0).setZero();
  for (int i = 1; i < n; ++i) m.vertices.col(i) = m.vertices.col(i - 1) + len[i - 1] * dir;
  for (int i = 0; i + 1 < n; ++i) m.edges.push_back({i, i + 1});
  SceneSettings q = p;
  if (p.variant == "mu1e12") q.compliance = 1e-12;
  Problem prob = make_cloth_problem(name, m, q);
  prob.particles.w[0] = 0;
  prob.particles.w[n - 1] = 1.0 / (p.particle_mass * p.mass_ratio);
  return prob;
}

Problem build_heavy_rope(const SceneSettings& p) { return build_end_mass_chain("heavy_rope", p); }
Problem build_pendulum(const SceneSettings& p) { return build_end_mass_chain("pendulum", p); }

}  // namespace

void flatten_some_tets(TetMesh& m) {
  // Every 50th tet: its last vertex is moved to 1e-3 of its height above the opposite face,
  // unless that would invert (or flatten below 1e-3) another tet using the vertex.
  std::vector<std::vector<int>> incident(m.vertices.cols());
  for (size_t t = 0; t < m.tets.size(); ++t)
    for (int v : m.tets[t]) incident[v].push_back(static_cast<int>(t));
  auto vol = [&](int t) {
    const auto& e = m.tets[t];
    return tet_volume(m.vertices.col(e[0]), m.vertices.col(e[1]), m.vertices.col(e[2]), m.vertices.col(e[3]));
  };
  std::vector<double> v0(m.tets.size());
  for (size_t t = 0; t < m.tets.size(); ++t) v0[t] = vol(static_cast<int>(t));
  for (size_t t = 0; t < m.tets.size(); t += 50) {
    const auto e = m.tets[t];
    const Eigen::Vector3d a = m.vertices.col(e[0]), b = m.vertices.col(e[1]), c = m.vertices.col(e[2]);
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d d = m.vertices.col(e[3]);
    const double height = (d - a).dot(n);
    const Eigen::Vector3d keep = d;
    m.vertices.col(e[3]) = d - (1 - 1e-3) * height * n;
    bool ok = true;
    for (int s : incident[e[3]])
      if (s != static_cast<int>(t) && !(vol(s) > 1e-3 * v0[s])) ok = false;
    if (!ok) m.vertices.col(e[3]) = keep;
  }
}

void flatten_some_triangles(TriMesh& m) {
  // Every 50th triangle: its last vertex is moved to 1e-3 of its height above the opposite edge
  // (in the triangle's plane), unless that flips or flattens another triangle using the vertex.
  std::vector<std::vector<int>> incident(m.vertices.cols());
  for (size_t t = 0; t < m.triangles.size(); ++t)
    for (int v : m.triangles[t]) incident[v].push_back(static_cast<int>(t));
  auto normal = [&](int t) {
    const auto& e = m.triangles[t];
    return Eigen::Vector3d((m.vertices.col(e[1]) - m.vertices.col(e[0])).cross(m.vertices.col(e[2]) - m.vertices.col(e[0])));
  };
  std::vector<Eigen::Vector3d> n0(m.triangles.size());
  for (size_t t = 0; t < m.triangles.size(); ++t) n0[t] = normal(static_cast<int>(t));
  for (size_t t = 0; t < m.triangles.size(); t += 50) {
    const auto e = m.triangles[t];
    const Eigen::Vector3d a = m.vertices.col(e[0]), b = m.vertices.col(e[1]), c = m.vertices.col(e[2]);
    const Eigen::Vector3d u = (b - a).normalized();
    const Eigen::Vector3d foot = a + (c - a).dot(u) * u;
    m.vertices.col(e[2]) = foot + 1e-3 * (c - foot);
    bool ok = true;
    for (int s : incident[e[2]])
      if (s != static_cast<int>(t) && !(normal(s).dot(n0[s]) > 1e-3 * n0[s].squaredNorm())) ok = false;
    if (!ok) m.vertices.col(e[2]) = c;
  }
}

bool end_mass_scene(const std::string& scene) { return scene == "heavy_rope" || scene == "pendulum"; }

void apply_variant(const SceneSettings& p, Problem& prob) {
  if (p.variant == "rigid") {
    // Infinite stiffness (Goldenthal's method): every constraint has α = 0. With redundant
    // constraints A = ∇C M⁻¹ ∇Cᵀ is singular, which a global solver must report.
    for (auto& a : prob.distance.compliance) a = 0;
    for (auto& a : prob.tets.compliance) a = 0;
  }
  if (p.mass_ratio != 1 && !end_mass_scene(p.scene)) {  // the end-mass chains weigh their last particle only
    const int n = prob.particles.size();
    for (int i = 0; i < n; ++i) {
      if (prob.particles.w[i] == 0) continue;  // pins stay pinned
      const double s = n > 1 ? static_cast<double>(i) / (n - 1) : 0;
      prob.particles.w[i] = 1.0 / (p.particle_mass * (1 + (p.mass_ratio - 1) * s * s));
    }
  }
}

const std::vector<BuilderInfo>& scene_builders() {
  static const std::vector<BuilderInfo> b = {
      {"cloth_hang", "horizontal cloth, two corners pinned, gravity (paper Fig. 8)", build_cloth_hang},
      {"bar_hang", "tet bar with one end pinned under gravity (a cantilever)", build_bar_hang},
      {"squash", "mesh collapsed to its minimum y and released, no gravity (paper Figs. 13/17)", build_squash},
      {"twist_bar", "pre-twisted tet bar released, no gravity (paper's twist-bar energy plot)", build_twist_bar},
      {"cantilever", "tet bar with its left 1% fixed, under gravity (authors' reinit=beam)", build_cantilever},
      {"ball_drop", "tet ball falling onto the ground plane y = 0 (the one scene with a collider)", build_ball_drop},
      {"mass_chain", "chain pinned at one end, masses growing as i^2 up to mass_ratio, under gravity", build_mass_chain},
      {"heavy_rope", "stiff rope pinned at the top holding an end mass mass_ratio times a link particle's, released at angle",
       build_heavy_rope},
      {"pendulum", "multi-link pendulum, its last particle mass_ratio times as heavy, released at angle", build_pendulum},
  };
  return b;
}

void check_scene_keys(const SceneSettings& p) {
  // Scene keys that only some builders read are refused rather than silently ignored.
  const bool mesh_scene = p.scene == "squash" || p.scene == "twist_bar" || p.scene == "cantilever" || p.scene == "ball_drop";
  if (p.mesh_height != 0 && !mesh_scene)
    throw Error("parameter 'mesh_height' applies to the mesh scenes (squash, twist_bar, cantilever, ball_drop), not '" +
                p.scene + "'");
  if (p.init != "none" && p.scene != "squash")
    throw Error("parameter 'init' = '" + p.init + "' applies to the squash scene only, not '" + p.scene + "'");
  if (!p.mesh.empty() && !mesh_scene)
    throw Error("parameter 'mesh' = '" + p.mesh + "' applies to the mesh scenes (squash, twist_bar, cantilever, ball_drop), not '" +
                p.scene + "' (it builds its own mesh; use resolution)");
  if (p.twist != 0 && p.scene != "twist_bar")
    throw Error("parameter 'twist' applies to the twist_bar scene only, not '" + p.scene + "'");
  if (p.angle != 0 && !end_mass_scene(p.scene))
    throw Error("parameter 'angle' applies to the heavy_rope and pendulum scenes only, not '" + p.scene + "'");
  if (p.prestretch != 1 && p.scene != "bar_hang")
    throw Error("parameter 'prestretch' applies to the bar_hang scene only, not '" + p.scene + "'");
}

bool every_constraint_compliant(const SceneSettings& p) {
  if (p.variant == "rigid") return false;
  if (p.scene == "cloth_hang" || p.scene == "mass_chain") return p.compliance > 0;
  if (end_mass_scene(p.scene)) return p.compliance > 0 || p.variant == "mu1e12";  // mu1e12: links at 1e-12 m/N
  return true;  // tets: alpha = 1/(mu V), mu and V > 0
}

Problem build_problem(const SceneSettings& p) {
  validate(p);
  check_scene_keys(p);
  for (const auto& b : scene_builders())
    if (b.name == p.scene) {
      Problem prob = b.build(p);
      apply_pins_and_ground(p, prob);  // before the mass grading, which keeps pins pinned
      apply_variant(p, prob);
      prob.check();
      return prob;
    }
  std::string valid;
  for (const auto& b : scene_builders()) valid += (valid.empty() ? "" : ", ") + b.name;
  throw Error("unknown scene builder '" + p.scene + "' (valid: " + valid + ")");
}

}  // namespace xb
