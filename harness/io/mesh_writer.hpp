// Surface meshes of a run's frames as PLY (binary little-endian, or ASCII) for ParaView/Blender.
#pragma once

#include "../../problems/problem.hpp"

#include <string>

namespace xb {

// Writes the vertices x with the problem's surface triangles; a problem without a surface (a
// chain) gets its distance constraints as PLY edges, through a temporary file (atomic_file.hpp). Throws
// WriteError when the file cannot be written.
void write_ply(const std::string& path, const Problem& prob, const Eigen::Matrix3Xd& x, bool binary = true);

// DIR/<prefix>_NNNN.ply for frame NNNN (creating DIR).
std::string frame_ply_path(const std::string& dir, const std::string& prefix, int frame);

}  // namespace xb
