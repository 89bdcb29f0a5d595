#include "system_io.hpp"

#include "atomic_file.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <type_traits>
#include <vector>

namespace fs = std::filesystem;

namespace xb {

namespace {

using namespace h5;

template <class T>
void write_array(hid_t file, const char* name, const T* data, hsize_t n, hid_t type) {
  H lcpl = link_create_plist();
  H space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  check_id(space, std::string("dataspace of ") + name);
  H ds(H5Dcreate2(file, name, type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  check(ds < 0 ? -1 : 0, std::string("create dataset ") + name);
  if (n) check(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), std::string("write ") + name);
}

// A 1-D numeric dataset; integers are refused where floats are stored and the other way round
// only when T is an integer type (indices must not be rounded).
template <class T>
std::vector<T> read_array(hid_t file, const std::string& path, const std::string& name) {
  H ds = open_dataset(file, name, path);
  DataValue v = read_dataset(ds, path + ": " + name);
  if (auto* i = std::get_if<std::vector<long long>>(&v)) return std::vector<T>(i->begin(), i->end());
  if (auto* d = std::get_if<std::vector<double>>(&v); d && std::is_floating_point_v<T>) return std::vector<T>(d->begin(), d->end());
  throw Error(path + ": " + name + " holds " + (std::holds_alternative<std::vector<double>>(v) ? "floats" : "strings") +
              ", expected " + (std::is_floating_point_v<T> ? "numbers" : "integers"));
}

struct Silence {  // HDF5 prints error stacks by default; we report our own messages.
  Silence() { silence_errors(); }
};
const Silence silence_hdf5;

}  // namespace

std::string attr_text(const std::map<std::string, AttrValue>& attrs, const std::string& key) {
  auto it = attrs.find(key);
  return it == attrs.end() ? "" : attr_value_text(it->second, 17);
}

SparseMatrix jacobian_csr(const ConstraintGraph& graph, const Gradients& grad) {
  const int m = graph.num_constraints();
  SparseMatrix J(m, 3 * graph.num_particles());
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(12L * m);
  for (int j = 0; j < m; ++j)
    for (int s = 0; s < 4; ++s)
      if (const int p = graph.particles[j][s]; p >= 0)
        for (int d = 0; d < 3; ++d) t.emplace_back(j, 3 * p + d, grad[j][s][d]);
  J.setFromTriplets(t.begin(), t.end());  // every entry stored, zeros included: the pattern is the topology
  J.makeCompressed();
  return J;
}

void jacobian_from_csr(const SparseMatrix& J, ConstraintGraph& graph, Gradients& grad) {
  const int m = static_cast<int>(J.rows());
  graph.particles.assign(m, {-1, -1, -1, -1});
  grad.assign(m, {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  for (int j = 0; j < m; ++j) {
    int slot = -1;
    for (SparseMatrix::InnerIterator it(J, j); it; ++it) {
      const int p = static_cast<int>(it.col() / 3);
      if (slot < 0 || graph.particles[j][slot] != p) {
        if (++slot == 4) throw Error("J: row " + std::to_string(j) + " couples more than 4 particles");
        graph.particles[j][slot] = p;
      }
      grad[j][slot][it.col() % 3] = it.value();
    }
  }
}

namespace {
void write_csr(hid_t file, const std::string& group, const SparseMatrix& M) {
  std::vector<long long> indptr(M.outerIndexPtr(), M.outerIndexPtr() + M.rows() + 1);
  std::vector<long long> indices(M.innerIndexPtr(), M.innerIndexPtr() + M.nonZeros());
  write_array(file, (group + "/indptr").c_str(), indptr.data(), indptr.size(), H5T_NATIVE_LLONG);
  write_array(file, (group + "/indices").c_str(), indices.data(), indices.size(), H5T_NATIVE_LLONG);
  write_array(file, (group + "/data").c_str(), M.valuePtr(), static_cast<hsize_t>(M.nonZeros()), H5T_NATIVE_DOUBLE);
}

// A CSR matrix of `rows` × `cols` from /G/indptr, /G/indices, /G/data, every array checked.
SparseMatrix read_csr(hid_t file, const std::string& path, const std::string& g, long long rows, long long cols) {
  const auto indptr = read_array<long long>(file, path, g + "/indptr");
  const auto indices = read_array<long long>(file, path, g + "/indices");
  const auto data = read_array<double>(file, path, g + "/data");
  const long long nnz = static_cast<long long>(data.size());
  if (static_cast<long long>(indptr.size()) != rows + 1)
    throw Error(path + ": " + g + "/indptr has " + std::to_string(indptr.size()) + " entries, expected rows + 1 = " +
                std::to_string(rows + 1));
  if (indices.size() != data.size())
    throw Error(path + ": " + g + "/indices has " + std::to_string(indices.size()) + " entries and " + g + "/data " +
                std::to_string(nnz) + " (they must match)");
  if (rows > 2147483647LL || cols > 2147483647LL || nnz > 2147483647LL)
    throw Error(path + ": " + g + " too large for 32-bit indices");
  // Every row's range is checked before any entry is read: a row pointer past the arrays
  // must be reported as what it is, not as a bad index somewhere else.
  if (indptr.front() != 0) throw Error(path + ": " + g + "/indptr starts at " + std::to_string(indptr.front()) + ", expected 0");
  for (long long i = 0; i < rows; ++i)
    if (indptr[i + 1] < indptr[i] || indptr[i + 1] > nnz)
      throw Error(path + ": " + g + "/indptr is not non-decreasing within [0, " + std::to_string(nnz) + "] at row " +
                  std::to_string(i) + " (it overruns or goes back)");
  if (indptr.back() != nnz)
    throw Error(path + ": " + g + "/indptr ends at " + std::to_string(indptr.back()) + ", but " + g + "/indices and " + g +
                "/data have " + std::to_string(nnz) + " entries");
  SparseMatrix M(rows, cols);
  M.resizeNonZeros(static_cast<long>(data.size()));
  for (long long i = 0; i <= rows; ++i) M.outerIndexPtr()[i] = static_cast<int>(indptr[i]);
  for (long long i = 0; i < rows; ++i) {
    for (long long k = indptr[i]; k < indptr[i + 1]; ++k) {
      if (indices[k] < 0 || indices[k] >= cols || (k > indptr[i] && indices[k] <= indices[k - 1]))
        throw Error(path + ": " + g + "/indices out of range or unsorted in row " + std::to_string(i));
      M.innerIndexPtr()[k] = static_cast<int>(indices[k]);
      M.valuePtr()[k] = data[k];
    }
  }
  return M;
}
}  // namespace

void write_system_h5(TmpFile& out, const CapturedSystem& sys) {
  const SparseMatrix& A = sys.A;
  const Vector& b = sys.b;
  if (A.rows() != A.cols() || A.rows() != b.size()) throw Error("write_system_h5: A is not square or b has the wrong size");
  const Guard guard;  // h5handle.hpp
  if (!A.isCompressed()) throw Error("write_system_h5: A must be compressed");
  std::vector<char> image;
  {
    H file = create_memory_file();  // written by us, whole or not at all (h5io.hpp)
    const long long n = A.rows(), nnz = A.nonZeros();
    write_csr(file, "/A", A);
    write_array(file, "/b", b.data(), static_cast<hsize_t>(n), H5T_NATIVE_DOUBLE);
    if (sys.has_primal()) {
      write_csr(file, "/J", jacobian_csr(sys.graph, sys.grad));
      const auto& w = sys.graph.w;
      write_array(file, "/inverse_mass", w.data(), static_cast<hsize_t>(w.size()), H5T_NATIVE_DOUBLE);
      write_array(file, "/alpha_tilde", sys.alpha_tilde.data(), static_cast<hsize_t>(sys.alpha_tilde.size()), H5T_NATIVE_DOUBLE);
      write_array(file, "/positions", sys.x.data(), static_cast<hsize_t>(sys.x.size()), H5T_NATIVE_DOUBLE);
    }
    for (const auto& [k, v] : sys.attrs) write_attr(file, k, v);
    write_attr(file, "kind", std::string("dual_system"));
    write_attr(file, "generator", std::string("xpbd-bench"));
    write_attr(file, "rows", n);
    write_attr(file, "nnz", nnz);
    image = file_image(file);
  }
  out.write(image.data(), image.size());
}

void write_system_h5(const std::string& path, const CapturedSystem& sys) {
  make_parent(path);
  TmpFile out(path);
  write_system_h5(out, sys);
  out.commit();
}

CapturedSystem read_system_h5(const std::string& path) {
  const Guard guard;
  H file = open_file(path);
  CapturedSystem s;
  s.attrs = read_attrs(file, path + ": root");
  if (attr_text(s.attrs, "kind") != "dual_system")
    throw Error(path + ": not a captured system (attribute kind = \"dual_system\" missing; write one with `xpbd-bench capture`)");
  if (const Kind k = link_kind(file, "/A"); k != Kind::group)
    throw Error(path + ": not a captured system (/A is " + kind_text(k) + ", expected a group)");
  const auto b = read_array<double>(file, path, "/b");
  const long long n = static_cast<long long>(b.size());
  if (n == 0) throw Error(path + ": /b is empty (a captured system has at least one row)");
  s.A = read_csr(file, path, "/A", n, n);
  s.b = Eigen::Map<const Vector>(b.data(), n);
  if (const Kind k = link_kind(file, "/J"); k != Kind::missing) {
    if (k != Kind::group) throw Error(path + ": /J is " + std::string(kind_text(k)) + ", expected a group");
    const auto w = read_array<double>(file, path, "/inverse_mass");
    const auto at = read_array<double>(file, path, "/alpha_tilde");
    const auto x = read_array<double>(file, path, "/positions");
    const long long np = static_cast<long long>(w.size());
    if (static_cast<long long>(at.size()) != n) throw Error(path + ": /alpha_tilde has " + std::to_string(at.size()) + " entries, expected rows = " + std::to_string(n));
    if (static_cast<long long>(x.size()) != 3 * np) throw Error(path + ": /positions has " + std::to_string(x.size()) + " entries, expected 3 x particles = " + std::to_string(3 * np));
    jacobian_from_csr(read_csr(file, path, "/J", n, 3 * np), s.graph, s.grad);
    s.graph.w = Eigen::Map<const Eigen::VectorXd>(w.data(), np);
    s.alpha_tilde = Eigen::Map<const Eigen::VectorXd>(at.data(), n);
    s.x = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, np);
  }
  return s;
}

std::vector<std::string> write_captured_system(const std::string& prefix, const CapturedSystem& sys) {
  // Every file is written to its temporary file first and only then are they renamed, so a full disk
  // leaves the files of an earlier capture with this prefix as they were, all of them.
  make_parent(prefix);
  std::vector<std::unique_ptr<TmpFile>> files;
  try {
    auto next = [&](const std::string& suffix) -> TmpFile& { return *files.emplace_back(std::make_unique<TmpFile>(prefix + suffix)); };
    write_matrix_market(next("_A.mtx"), sys.A);
    write_matrix_market(next("_b.mtx"), sys.b);
    if (sys.has_primal() && (sys.alpha_tilde.array() > 0).all()) {
      PrimalSystem ps(sys.graph);
      ps.fill(sys.grad, sys.alpha_tilde);
      Vector f;
      ps.rhs(sys.grad, sys.alpha_tilde, sys.b, f);
      write_matrix_market(next("_K.mtx"), ps.K());
      write_matrix_market(next("_f.mtx"), f);
    }
    write_system_h5(next(".h5"), sys);
    for (auto& f : files) f->finish();  // every byte on disk before the first rename
  } catch (const WriteError& e) {
    throw WriteError(e.path, e.err, std::string(e.what()) + "; no file of " + prefix + " was replaced");
  }
  std::string replaced;
  for (auto& f : files) {  // the .h5 last, as it always was
    try {
      f->commit();
    } catch (const WriteError& e) {
      throw WriteError(e.path, e.err, std::string(e.what()) + (replaced.empty() ? "; no file of " + prefix + " was replaced" : "; already replaced: " + replaced));
    }
    replaced += (replaced.empty() ? "" : ", ") + f->target();
  }
  std::vector<std::string> written = {prefix + ".h5"};
  for (size_t i = 0; i + 1 < files.size(); ++i) written.push_back(files[i]->target());
  return written;
}

}  // namespace xb
