// Parallel (OpenMP) sparse and vector kernels on the raw CSR arrays.
#pragma once

#include "../core/sparse.hpp"

namespace xb {

// y = A x
void spmv(const SparseMatrix& A, const Vector& x, Vector& y);
// r = b − A x
void residual(const SparseMatrix& A, const Vector& x, const Vector& b, Vector& r);
double dot(const Vector& a, const Vector& b);
inline double norm2(const Vector& a) { return std::sqrt(dot(a, a)); }
// y += a x
void axpy(double a, const Vector& x, Vector& y);
// The diagonal of A (zero where a row has no diagonal entry).
Vector diagonal(const SparseMatrix& A);

}  // namespace xb
