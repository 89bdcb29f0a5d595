#include "mesh_writer.hpp"

#include "atomic_file.hpp"

#include "../../core/error.hpp"

#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace xb {

namespace {
template <class T>
void put(std::ostream& out, T v) {
  static_assert(std::endian::native == std::endian::little, "binary PLY is written little-endian");
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
}  // namespace

void write_ply(const std::string& path, const Problem& prob, const Eigen::Matrix3Xd& x, bool binary) {
  std::ostringstream out(std::ios::binary);  // in memory, then written whole or not at all
  const bool edges = prob.surface.empty();
  const size_t nf = edges ? prob.distance.size() : prob.surface.size();
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment xpbd-bench " << prob.name
      << "\nelement vertex " << x.cols() << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (edges)
    out << "element edge " << nf << "\nproperty int vertex1\nproperty int vertex2\n";
  else
    out << "element face " << nf << "\nproperty list uchar int vertex_indices\n";
  out << "end_header\n";
  if (binary) {
    for (int i = 0; i < x.cols(); ++i)
      for (int c = 0; c < 3; ++c) put(out, static_cast<float>(x(c, i)));
    if (edges) {
      for (const auto& e : prob.distance.idx) put(out, std::int32_t(e[0])), put(out, std::int32_t(e[1]));
    } else {
      for (const auto& f : prob.surface) {
        put(out, std::uint8_t(3));
        for (int v : f) put(out, std::int32_t(v));
      }
    }
  } else {
    out.precision(9);
    for (int i = 0; i < x.cols(); ++i) out << x(0, i) << " " << x(1, i) << " " << x(2, i) << "\n";
    if (edges)
      for (const auto& e : prob.distance.idx) out << e[0] << " " << e[1] << "\n";
    else
      for (const auto& f : prob.surface) out << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
  }
  const std::string bytes = std::move(out).str();
  write_file_atomically(path, bytes.data(), bytes.size());
}

std::string frame_ply_path(const std::string& dir, const std::string& prefix, int frame) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("--write-meshes: cannot create directory '" + dir + "': " + ec.message());
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%04d.ply", frame);
  return dir + "/" + prefix + buf;
}

}  // namespace xb
