#include "gauss_seidel.hpp"

#include "../../kernels.hpp"

namespace xb::amg {

void multicolor_gs_sweep(const SparseMatrix& A, const Vector& inv_diag, const Coloring& coloring, const Vector& b,
                         Vector& x, bool forward) {
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const int* order = coloring.order.data();
  for (int cc = 0; cc < coloring.num_colors; ++cc) {
    const int c = forward ? cc : coloring.num_colors - 1 - cc;
    const int lo = coloring.color_start[c], hi = coloring.color_start[c + 1];
    // Within one colour the rows are independent, so backward order inside it is irrelevant.
#pragma omp parallel for schedule(static) if (hi - lo > kMinParallelRows)
    for (int t = lo; t < hi; ++t) {
      const int i = order[t];
      double s = b[i];
      for (int k = outer[i]; k < outer[i + 1]; ++k) s -= val[k] * x[cols[k]];
      x[i] += inv_diag[i] * s;
    }
  }
}

GaussSeidelSmoother::GaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A)
    : opt_(opt), coloring_(greedy_coloring(A)), inv_diag_(inverse_diagonal(A)) {}

// The colouring depends on the pattern only.
void GaussSeidelSmoother::refresh(const SparseMatrix& A) { inv_diag_ = inverse_diagonal(A); }

void GaussSeidelSmoother::presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) {
  if (x_zero) x.setZero();
  for (int s = 0; s < opt_.sweeps; ++s) multicolor_gs_sweep(A, inv_diag_, coloring_, b, x, true);
}

void GaussSeidelSmoother::postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) {
  for (int s = 0; s < opt_.sweeps; ++s) multicolor_gs_sweep(A, inv_diag_, coloring_, b, x, false);
}

}  // namespace xb::amg
