#include "kernels.hpp"

namespace xb {

void spmv(const SparseMatrix& A, const Vector& x, Vector& y) {
  const int n = static_cast<int>(A.rows());
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  y.resize(n);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    double s = 0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * x[cols[k]];
    y[i] = s;
  }
}

void residual(const SparseMatrix& A, const Vector& x, const Vector& b, Vector& r) {
  const int n = static_cast<int>(A.rows());
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  r.resize(n);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k) s -= val[k] * x[cols[k]];
    r[i] = s;
  }
}

double dot(const Vector& a, const Vector& b) {
  const long n = a.size();
  double s = 0;
#pragma omp parallel for reduction(+ : s) schedule(static)
  for (long i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

void axpy(double a, const Vector& x, Vector& y) {
  const long n = x.size();
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) y[i] += a * x[i];
}

Vector diagonal(const SparseMatrix& A) {
  const int n = static_cast<int>(A.rows());
  Vector d = Vector::Zero(n);
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i)
    for (int k = outer[i]; k < outer[i + 1]; ++k)
      if (cols[k] == i) d[i] = val[k];
  return d;
}

}  // namespace xb
