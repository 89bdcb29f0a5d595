// xpbd_bench.AmgHierarchy: the in-house AMG hierarchy (solvers/amg/hierarchy.hpp) built by the
// C++ setup for a given matrix and amg.* settings, as mgpbd builds it, and its levels as
// scipy/numpy objects through the one export (solvers/amg/hierarchy_export.hpp): what the GPU
// solve phase (python/xpbd_bench/gpu.py) runs. A refresh takes new values on the same pattern.
#include "bindings.hpp"
#include "convert.hpp"

#include "core/error.hpp"
#include "solvers/amg/hierarchy_export.hpp"

#include <nanobind/ndarray.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/string.h>

#include <cstring>
#include <map>

namespace xb::py {

namespace {

using namespace nb::literals;
using IndexArray = nb::ndarray<const int, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using ValueArray = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using ModesArray = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;

// A CSR matrix from its arrays (sorted, no duplicates: the package's wrapper makes them so).
SparseMatrix csr_from(long n, const IndexArray& indptr, const IndexArray& indices, const ValueArray& data) {
  if (indptr.shape(0) != static_cast<size_t>(n) + 1) throw Error("AmgHierarchy: indptr has the wrong length");
  const long nnz = indptr.data()[n];
  if (indices.shape(0) != static_cast<size_t>(nnz) || data.shape(0) != static_cast<size_t>(nnz))
    throw Error("AmgHierarchy: indices and data must have indptr[-1] entries");
  for (long k = 0; k < nnz; ++k)
    if (indices.data()[k] < 0 || indices.data()[k] >= n) throw Error("AmgHierarchy: a column index is out of range");
  return Eigen::Map<const SparseMatrix>(n, n, nnz, indptr.data(), indices.data(), data.data());
}

// A copy that numpy owns: a read-only scipy matrix whose arrays live in a heap SparseMatrix.
nb::object csr_copy(const SparseMatrix& A) {
  auto* M = new SparseMatrix(A);
  M->makeCompressed();
  nb::capsule owner(M, [](void* p) noexcept { delete static_cast<SparseMatrix*>(p); });
  return csr_view(*M, owner);
}

nb::object ints(const std::vector<int>& v) {
  return vector_copy(Eigen::Map<const Eigen::VectorXi>(v.data(), static_cast<Eigen::Index>(v.size())).cast<double>())
      .attr("astype")("int64");
}

nb::dict smoother_dict(const amg::SmootherExport& s) {
  nb::dict d;
  d["kind"] = s.kind;
  d["polynomial"] = s.polynomial;
  d["sweeps"] = s.sweeps;
  d["degree"] = s.degree;
  d["lambda_max"] = s.lambda_max;
  d["lower"] = s.lower;
  d["upper"] = s.upper;
  Eigen::MatrixXd steps(static_cast<Eigen::Index>(s.steps.size()), 2);
  for (size_t k = 0; k < s.steps.size(); ++k) steps.row(static_cast<Eigen::Index>(k)) << s.steps[k][0], s.steps[k][1];
  d["steps"] = matrix_copy(steps);
  d["inv_diag"] = s.node_start.empty() ? vector_copy(s.inv_diag) : nb::none();
  d["node_start"] = s.node_start.empty() ? nb::none() : ints(s.node_start);
  d["block_inv"] = s.node_start.empty()
                       ? nb::none()
                       : vector_copy(Eigen::Map<const Eigen::VectorXd>(s.block_inv.data(), static_cast<Eigen::Index>(s.block_inv.size())));
  return d;
}

struct AmgHierarchy {
  SparseMatrix A;  // the hierarchy's level 0 points here
  amg::Hierarchy h;
  double setup_seconds = 0;

  AmgHierarchy(long n, const IndexArray& indptr, const IndexArray& indices, const ValueArray& data, int block_size,
               nb::object near_kernel, const std::map<std::string, std::string>& settings) {
    A = csr_from(n, indptr, indices, data);
    amg::AmgOptions opt;
    int seed = 1;  // SolverSettings::seed's default
    for (const auto& [key, value] : settings) {
      if (key == "seed") {
        try {
          seed = std::stoi(value);
        } catch (const std::exception&) {
          throw Error("AmgHierarchy: seed = '" + value + "' is not an integer");
        }
      } else {
        set_setting(amg_settings(), opt, key, value, "AmgHierarchy");
      }
    }
    opt.near_kernel.seed = opt.smoother.seed = static_cast<unsigned>(seed);  // as mgpbd does
    Eigen::MatrixXd B;
    if (!near_kernel.is_none()) {
      const ModesArray m = nb::cast<ModesArray>(near_kernel);
      if (m.shape(0) != static_cast<size_t>(n)) throw Error("AmgHierarchy: near_kernel must have one row per row of A");
      B = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          m.data(), static_cast<Eigen::Index>(m.shape(0)), static_cast<Eigen::Index>(m.shape(1)));
    }
    nb::gil_scoped_release release;
    h.setup(A, opt, {block_size, near_kernel.is_none() ? nullptr : &B});
  }

  bool refresh(const IndexArray& indptr, const IndexArray& indices, const ValueArray& data) {
    const long n = A.rows();
    if (indptr.shape(0) != static_cast<size_t>(n) + 1 || indices.shape(0) != static_cast<size_t>(A.nonZeros()) ||
        data.shape(0) != static_cast<size_t>(A.nonZeros()) ||
        std::memcmp(indptr.data(), A.outerIndexPtr(), (n + 1) * sizeof(int)) != 0 ||
        std::memcmp(indices.data(), A.innerIndexPtr(), A.nonZeros() * sizeof(int)) != 0)
      throw Error("AmgHierarchy.refresh: the matrix's pattern is not the one it was set up with (a new setup is needed)");
    std::memcpy(A.valuePtr(), data.data(), A.nonZeros() * sizeof(double));
    nb::gil_scoped_release release;
    return h.refresh(A);
  }

  nb::dict export_levels() const {
    const amg::HierarchyExport e = amg::export_hierarchy(h);
    nb::dict d;
    d["precision"] = e.precision;
    d["coarse_solver"] = e.coarse_solver;
    d["block_size"] = e.block_size;
    nb::list levels;
    for (const auto& L : e.levels) {
      nb::dict l;
      l["A"] = csr_copy(L.A);
      l["P"] = L.P.rows() ? csr_copy(L.P) : nb::none();
      l["R"] = L.R.rows() ? csr_copy(L.R) : nb::none();
      l["smoother"] = L.smoother.kind.empty() ? nb::none() : nb::object(smoother_dict(L.smoother));
      levels.append(l);
    }
    d["levels"] = levels;
    return d;
  }

  nb::object vcycle(const ValueArray& b) {
    if (b.shape(0) != static_cast<size_t>(A.rows())) throw Error("AmgHierarchy.vcycle: b has the wrong length");
    const Vector bv = Eigen::Map<const Vector>(b.data(), A.rows());
    Vector x;
    {
      nb::gil_scoped_release release;
      h.vcycle(bv, x);
    }
    return vector_copy(x);
  }
};

}  // namespace

void bind_amg(nb::module_& m) {
  nb::class_<AmgHierarchy>(m, "AmgHierarchy",
                           "The in-house AMG hierarchy of mgpbd for one matrix (use xpbd_bench.amg_hierarchy).")
      .def(nb::init<long, const IndexArray&, const IndexArray&, const ValueArray&, int, nb::object,
                    const std::map<std::string, std::string>&>(),
           "n"_a, "indptr"_a, "indices"_a, "data"_a, "block_size"_a, "near_kernel"_a.none(), "settings"_a)
      .def("_refresh", &AmgHierarchy::refresh, "indptr"_a, "indices"_a, "data"_a)
      .def("export", &AmgHierarchy::export_levels,
           "The levels as mgpbd's V-cycle applies them: a dict of precision, coarse_solver, block_size and levels "
           "(each: A, P, R as scipy CSR copies, smoother as a dict or None).")
      .def("_vcycle", &AmgHierarchy::vcycle, "b"_a)
      .def_prop_ro("num_levels", [](const AmgHierarchy& a) { return a.h.num_levels(); })
      .def_prop_ro("operator_complexity", [](const AmgHierarchy& a) { return a.h.operator_complexity(); })
      .def_prop_ro("options", [](const AmgHierarchy& a) {
        nb::dict d;
        for (const auto& f : amg_settings()) d[f.key.c_str()] = setting_text(f, a.h.options());
        return d;
      }, "the resolved amg.* settings (auto replaced by what it means for this matrix), as text");
}

}  // namespace xb::py
