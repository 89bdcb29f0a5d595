// C++ data as numpy / scipy objects and back, for the bindings of python/. Views share the C++
// arrays (no copy, read-only) and keep `owner` alive; copies own their memory.
#pragma once

#include "core/sparse.hpp"
#include "harness/io/recorder.hpp"

#include <nanobind/nanobind.h>

#include <Eigen/Dense>

#include <string>

namespace xb::py {

namespace nb = nanobind;

// A read-only numpy view of n doubles. An empty owner means the view is valid only as long as
// the C++ data (the solver protocol's A and b: until the next setup / the end of the call).
nb::object vector_view(const double* data, size_t n, nb::handle owner);
// numpy arrays owning a copy: a vector (n,), a matrix (rows, cols), positions (n, 3).
nb::object vector_copy(const Eigen::VectorXd& v);
nb::object matrix_copy(const Eigen::MatrixXd& m);
nb::object positions_copy(const Eigen::Matrix3Xd& x);
// scipy.sparse.csr_matrix over A's compressed arrays (values, column indices, row pointers as
// read-only views kept alive by owner): no copy.
nb::object csr_view(const SparseMatrix& A, nb::handle owner);

// Any array-like as a Vector of exactly n finite doubles; otherwise xb::Error saying what `what`
// returned (shape, type, or how many entries are NaN/inf).
Vector to_vector(nb::handle obj, Eigen::Index n, const std::string& what);

// "TypeName: message" of a Python exception (the exception is consumed).
std::string describe(const nb::python_error& e);

// A run of a results file as a dict, as plots/xbruns.py loads one: "name", "attrs" (every
// attribute) and "data" (every dataset as a numpy array, strings as a list); a summary and a
// dataset may share a name (wall_time, relative_dual_residual).
nb::dict record_to_dict(const RunRecord& r);
nb::object attr_to_python(const AttrValue& v);

}  // namespace xb::py
