// Mesh generators: the cloth grid and the tet bar.
#pragma once

#include "mesh.hpp"

namespace xb {

// An N×N-cell cloth grid in the xz-plane at height y, side `size`, one diagonal per quad:
// (N+1)² vertices (row-major, vertex (i,k) = i·(N+1)+k), 2N(N+1) + N² edges.
TriMesh make_cloth_grid(int N, double size, double y);

// A bar of nx×ny×nz cubes of side h (x from 0 to nx·h), each cube split into 6 tets along its
// main diagonal (Kuhn/Freudenthal; conforming across faces): (nx+1)(ny+1)(nz+1) vertices,
// 6·nx·ny·nz tets.
TetMesh make_tet_bar(int nx, int ny, int nz, double h);

}  // namespace xb
