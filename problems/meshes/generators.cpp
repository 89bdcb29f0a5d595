#include "generators.hpp"

#include <algorithm>
#include <map>
#include <utility>

namespace xb {

double tet_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

std::vector<std::array<int, 3>> boundary_faces(const TetMesh& mesh) {
  // Each face keyed by its sorted vertices; a face seen once is on the boundary.
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  for (const auto& t : mesh.tets) {
    // Faces opposite each vertex, ordered so that the normal points away from it for a
    // positively oriented tet.
    const std::array<std::array<int, 3>, 4> f = {{{t[1], t[2], t[3]}, {t[0], t[3], t[2]}, {t[0], t[1], t[3]}, {t[0], t[2], t[1]}}};
    for (const auto& tri : f) {
      auto key = tri;
      std::sort(key.begin(), key.end());
      auto [it, fresh] = faces.try_emplace(key, 0, tri);
      ++it->second.first;
    }
  }
  std::vector<std::array<int, 3>> out;
  for (const auto& [key, v] : faces)
    if (v.first == 1) out.push_back(v.second);
  return out;
}

TriMesh make_cloth_grid(int N, double size, double y) {
  TriMesh m;
  const int n1 = N + 1;
  m.vertices.resize(3, n1 * n1);
  for (int i = 0; i < n1; ++i)
    for (int k = 0; k < n1; ++k) m.vertices.col(i * n1 + k) = Eigen::Vector3d(size * k / N, y, size * i / N);
  auto id = [n1](int i, int k) { return i * n1 + k; };
  // Edges strip by strip (row i's horizontal edges, then the vertical and diagonal edges up to
  // row i + 1), so that a contiguous block of constraint rows is a band of the cloth: the MPI
  // solvers split A into contiguous row blocks.
  for (int i = 0; i < n1; ++i) {
    for (int k = 0; k < N; ++k) m.edges.push_back({id(i, k), id(i, k + 1)});
    if (i == N) break;
    for (int k = 0; k < n1; ++k) m.edges.push_back({id(i, k), id(i + 1, k)});
    for (int k = 0; k < N; ++k) {
      m.edges.push_back({id(i, k), id(i + 1, k + 1)});
      m.triangles.push_back({id(i, k), id(i + 1, k + 1), id(i, k + 1)});
      m.triangles.push_back({id(i, k), id(i + 1, k), id(i + 1, k + 1)});
    }
  }
  return m;
}

TetMesh make_tet_bar(int nx, int ny, int nz, double h) {
  TetMesh m;
  auto id = [&](int i, int j, int k) { return (i * (ny + 1) + j) * (nz + 1) + k; };
  m.vertices.resize(3, (nx + 1) * (ny + 1) * (nz + 1));
  for (int i = 0; i <= nx; ++i)
    for (int j = 0; j <= ny; ++j)
      for (int k = 0; k <= nz; ++k) m.vertices.col(id(i, j, k)) = Eigen::Vector3d(i * h, j * h, k * h);
  // The six paths from corner 000 to 111 along the cube's edges, one per axis order.
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k)
        for (const auto& pm : perms) {
          std::array<int, 3> c = {i, j, k};
          std::array<int, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[pm[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          if (tet_volume(m.vertices.col(t[0]), m.vertices.col(t[1]), m.vertices.col(t[2]), m.vertices.col(t[3])) < 0)
            std::swap(t[2], t[3]);
          m.tets.push_back(t);
        }
  return m;
}

}  // namespace xb
