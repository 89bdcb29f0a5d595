// The CSR currency of the project: row-major, 32-bit indices, sorted columns, compressed.
#pragma once
#include <Eigen/Sparse>

namespace xb {
// S: the storage precision (double; float for the V-cycle's single-precision copy).
template <class S>
using CsrOf = Eigen::SparseMatrix<S, Eigen::RowMajor, int>;
template <class S>
using VectorOf = Eigen::Matrix<S, Eigen::Dynamic, 1>;
using SparseMatrix = CsrOf<double>;
using Vector = Eigen::VectorXd;

// dst takes src's arrays. Eigen 3.4's SparseMatrix has no move constructor or move assignment:
// std::move(m), assigning a returned matrix and moving a struct that holds one all copy every
// array (on cloth 256² that was a third of the primal AMG setup).
inline void take(SparseMatrix& dst, SparseMatrix&& src) { dst.swap(src); }
}  // namespace xb
