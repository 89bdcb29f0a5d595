// The CSR currency of the project: row-major, 32-bit indices, sorted columns, compressed.
#pragma once
#include <Eigen/Sparse>

namespace xb {
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using Vector = Eigen::VectorXd;
}  // namespace xb
