// The parallel kernels against plain Eigen: row blocks cover the rows once, in order, with
// balanced non-zeros; the fused SpMV + dot and PCG update equal their unfused forms (the fused
// Chebyshev smoother: tests/solvers/amg/relaxation/test_chebyshev.cpp).
#include "solvers/kernels.hpp"

#include "solvers/amg/amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;

TEST(Kernels, RowBlocksCoverTheRowsWithBalancedNonZeros) {
  const SparseMatrix A = xb::test::poisson2d(37);
  const int n = static_cast<int>(A.rows());
  for (int T : {1, 2, 3, 7}) {
    int next = 0;
    for (int t = 0; t < T; ++t) {
      int lo, hi;
      row_block(A.outerIndexPtr(), n, t, T, lo, hi);
      EXPECT_EQ(lo, next);
      EXPECT_LE(lo, hi);
      const long nnz = A.outerIndexPtr()[hi] - A.outerIndexPtr()[lo];
      EXPECT_LE(std::abs(nnz - A.nonZeros() / T), 10) << T;  // ≤ 2 rows of 5 off the share
      next = hi;
    }
    EXPECT_EQ(next, n);
  }
}

TEST(Kernels, FusedKernelsEqualTheirUnfusedForms) {
  const SparseMatrix A = xb::test::poisson3d(9);
  const Vector x = xb::test::random_vector(A.rows(), 1), b = xb::test::random_vector(A.rows(), 2);
  Vector y, r;
  const double xy = spmv_dot(A, x, y);
  const Vector ref = A * x;
  EXPECT_LE((y - ref).norm(), 1e-14 * ref.norm());
  EXPECT_NEAR(xy, x.dot(ref), 1e-12 * std::abs(x.dot(ref)));
  residual(A, x, b, r);
  EXPECT_LE((r - (b - ref)).norm(), 1e-14 * b.norm());
  Vector xx = b, rr = r;
  const double rr2 = cg_update(0.3, x, y, xx, rr);
  EXPECT_LE((xx - (b + 0.3 * x)).norm(), 1e-14 * xx.norm());
  EXPECT_LE((rr - (r - 0.3 * ref)).norm(), 1e-14 * rr.norm());
  EXPECT_NEAR(rr2, rr.squaredNorm(), 1e-12 * rr2);
}
