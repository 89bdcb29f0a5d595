// The CSR currency of the project: row-major, 32-bit indices, sorted columns, compressed.
#pragma once
#include <Eigen/Sparse>

namespace xb {
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using Vector = Eigen::VectorXd;

// dst takes src's arrays. Eigen 3.4's SparseMatrix has no move constructor or move assignment:
// std::move(m), assigning a returned matrix and moving a struct that holds one all copy every
// array (on cloth 256² that was a third of the primal AMG setup).
inline void take(SparseMatrix& dst, SparseMatrix&& src) { dst.swap(src); }
}  // namespace xb
