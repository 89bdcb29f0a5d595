// Plain meshes as generators and readers produce them, before they become a Problem.
#pragma once

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace xb {

struct TetMesh {
  Eigen::Matrix3Xd vertices;
  std::vector<std::array<int, 4>> tets;  // positively oriented
};

struct TriMesh {
  Eigen::Matrix3Xd vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<int, 2>> edges;  // unique edges (for cloth: the distance constraints)
};

// Signed volume of tet (a, b, c, d): det[b−a, c−a, d−a]/6.
double tet_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d);

// Boundary triangles of a tet mesh (faces used by one tet), outward oriented.
std::vector<std::array<int, 3>> boundary_faces(const TetMesh& mesh);

}  // namespace xb
