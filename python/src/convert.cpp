#include "convert.hpp"

#include "core/error.hpp"

#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>

#include <cstring>
#include <memory>

namespace xb::py {

namespace {

using namespace nb::literals;

// A numpy array of `shape` that owns `data` (freed when the array goes).
nb::object owned(std::unique_ptr<double[]> data, std::initializer_list<size_t> shape) {
  double* p = data.release();
  nb::capsule owner(p, [](void* q) noexcept { delete[] static_cast<double*>(q); });
  return nb::ndarray<nb::numpy, double>(p, shape, owner).cast();
}

std::unique_ptr<double[]> copy_of(const double* src, size_t n) {
  auto p = std::make_unique<double[]>(n ? n : 1);
  if (n) std::memcpy(p.get(), src, n * sizeof(double));
  return p;
}

template <class T>
nb::object view(const T* data, size_t n, nb::handle owner) {
  return nb::ndarray<nb::numpy, const T, nb::ndim<1>>(data, {n}, owner).cast();
}

}  // namespace

nb::object vector_view(const double* data, size_t n, nb::handle owner) { return view(data, n, owner); }

nb::object vector_copy(const Eigen::VectorXd& v) {
  return owned(copy_of(v.data(), static_cast<size_t>(v.size())), {static_cast<size_t>(v.size())});
}

nb::object matrix_copy(const Eigen::MatrixXd& m) {
  // Row-major for numpy's default layout.
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = m;
  return owned(copy_of(r.data(), static_cast<size_t>(r.size())), {static_cast<size_t>(m.rows()), static_cast<size_t>(m.cols())});
}

nb::object positions_copy(const Eigen::Matrix3Xd& x) {
  // Matrix3Xd is column-major, so particle p's x, y, z are contiguous: (n, 3) row-major as it is.
  return owned(copy_of(x.data(), static_cast<size_t>(x.size())), {static_cast<size_t>(x.cols()), 3});
}

nb::object csr_view(const SparseMatrix& A, nb::handle owner) {
  if (!A.isCompressed()) throw Error("csr_view: the matrix is not compressed");
  const size_t nnz = static_cast<size_t>(A.nonZeros());
  nb::object data = view(A.valuePtr(), nnz, owner);
  nb::object indices = view(A.innerIndexPtr(), nnz, owner);
  nb::object indptr = view(A.outerIndexPtr(), static_cast<size_t>(A.rows()) + 1, owner);
  nb::object csr = nb::module_::import_("scipy.sparse").attr("csr_matrix");
  return csr(nb::make_tuple(data, indices, indptr), "shape"_a = nb::make_tuple(A.rows(), A.cols()), "copy"_a = false);
}

Vector to_vector(nb::handle obj, Eigen::Index n, const std::string& what) {
  nb::module_ np = nb::module_::import_("numpy");
  nb::object arr;
  try {
    arr = np.attr("ascontiguousarray")(obj, "dtype"_a = "float64");
  } catch (nb::python_error& e) {
    throw Error(what + " returned " + nb::cast<std::string>(nb::str(obj.type().attr("__name__"))) +
                ", not an array of floats (" + describe(e) + ")");
  }
  const std::string shape = nb::cast<std::string>(nb::repr(arr.attr("shape")));
  const long long ndim = PyLong_AsLongLong(arr.attr("ndim").ptr());
  const long long rows = ndim == 1 ? PyLong_AsLongLong(nb::object(arr.attr("shape"))[0].ptr()) : -1;
  if (ndim != 1 || rows != n) throw Error(what + " returned an array of shape " + shape + "; expected (" + std::to_string(n) + ",)");
  nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu> a;
  if (!nb::try_cast(arr, a)) throw Error(what + ": internal: the float64 array is not readable");
  Vector x(n);
  if (n) std::memcpy(x.data(), a.data(), static_cast<size_t>(n) * sizeof(double));
  if (!x.allFinite()) {
    const auto bad = (!x.array().isFinite()).count();
    throw Error(what + " returned a solution with " + std::to_string(bad) + " non-finite entries (NaN or inf) of " +
                std::to_string(n));
  }
  return x;
}

std::string describe(const nb::python_error& e) {
  const std::string type = nb::cast<std::string>(e.type().attr("__name__"));
  const std::string msg = nb::cast<std::string>(nb::str(e.value()));
  return msg.empty() ? type : type + ": " + msg;
}

nb::object attr_to_python(const AttrValue& v) {
  if (auto* i = std::get_if<long long>(&v)) return nb::int_(*i);
  if (auto* d = std::get_if<double>(&v)) return nb::float_(*d);
  return nb::str(std::get<std::string>(v).c_str());
}

nb::dict record_to_dict(const RunRecord& r) {
  nb::dict attrs, data;
  for (const auto& [k, v] : r.attrs) attrs[k.c_str()] = attr_to_python(v);
  for (const auto& [k, v] : r.datasets) {
    if (auto* dv = std::get_if<std::vector<double>>(&v)) {
      data[k.c_str()] = owned(copy_of(dv->data(), dv->size()), {dv->size()});
    } else if (auto* iv = std::get_if<std::vector<long long>>(&v)) {
      auto p = std::make_unique<long long[]>(iv->size() ? iv->size() : 1);
      std::copy(iv->begin(), iv->end(), p.get());
      long long* raw = p.release();
      nb::capsule owner(raw, [](void* q) noexcept { delete[] static_cast<long long*>(q); });
      data[k.c_str()] = nb::ndarray<nb::numpy, long long>(raw, {iv->size()}, owner).cast();
    } else {
      nb::list l;
      for (const auto& s : std::get<std::vector<std::string>>(v)) l.append(nb::str(s.c_str()));
      data[k.c_str()] = l;
    }
  }
  nb::dict d;
  d["name"] = r.name;
  d["attrs"] = attrs;
  d["data"] = data;
  return d;
}

}  // namespace xb::py
