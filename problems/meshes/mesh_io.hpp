// Tet-mesh readers: TetGen .node/.ele, gmsh .msh (2.2 and 4.1 ASCII), medit .mesh.
//
// Every reader ends in the same checks (finish_tet_mesh):
//  - coordinates must be finite (a NaN or Inf is an error naming its line);
//  - indices must be in range, and no tet may repeat a vertex;
//  - tets with negative signed volume are re-oriented (two vertices swapped) and counted in
//    MeshReadReport::flipped;
//  - a tet whose |volume| ≤ degenerate_volume_ratio × the median |volume| of the mesh is
//    degenerate: an error naming its line (such a tet has α = 1/(μV) → ∞ and Dm⁻¹ undefined);
//  - a vertex no tet uses is an error (it would be a free particle with no constraint,
//    usually a sign of a broken export), naming the vertex's line.
// Malformed files (truncated, wrong counts, bad numbers, unknown sections, binary .msh) end in
// xb::Error with one line "FILE:LINE: what is wrong". Nothing here crashes on bad input.
#pragma once

#include "mesh.hpp"

#include <string>
#include <vector>

namespace xb {

// |V_t| ≤ this × median |V| → degenerate. A TetGen -q mesh of a smooth surface has its smallest
// tets within ~1e-3 of the median; 1e-8 flags only tets that are numerically flat (e.g. four
// coplanar points with rounding noise) while accepting strongly graded meshes.
constexpr double degenerate_volume_ratio = 1e-8;

struct MeshReadReport {
  std::string format;               // "tetgen", "gmsh 2.2", "gmsh 4.1", "medit"
  int flipped = 0;                  // tets re-oriented to positive volume
  std::vector<std::string> notes;   // e.g. "ignored 1200 triangles (type 2)"
};

// By extension: .node or .ele (the pair is found by base name), .msh, .mesh.
TetMesh read_tet_mesh(const std::string& path, MeshReadReport* report = nullptr);

TetMesh read_tetgen(const std::string& node_path, const std::string& ele_path, MeshReadReport* report = nullptr);
TetMesh read_gmsh(const std::string& path, MeshReadReport* report = nullptr);
TetMesh read_medit(const std::string& path, MeshReadReport* report = nullptr);

// The shared checks above. Vertex i was read at vertex_file:vertex_line[i], tet t at
// tet_file:tet_line[t] (named in the error messages).
void finish_tet_mesh(TetMesh& mesh, const std::string& vertex_file, const std::vector<int>& vertex_line,
                     const std::string& tet_file, const std::vector<int>& tet_line, MeshReadReport* report);

}  // namespace xb
