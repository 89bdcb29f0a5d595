// The parallel kernels against plain Eigen: row blocks cover the rows once, in order, with
// balanced non-zeros; the fused SpMV + dot and PCG update equal their unfused forms (the fused
// Chebyshev smoother: tests/solvers/amg/relaxation/test_chebyshev.cpp); the sums are the same
// bits for any thread count.
#include "solvers/kernels.hpp"

#include "core/reduce.hpp"
#include "solvers/amg/amg_test_support.hpp"

#include <gtest/gtest.h>

#include <omp.h>

#include <cstring>

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

namespace {
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Σ_i f(i) by core/reduce.hpp's definition: chunks in index order, chunk sums in chunk order.
template <class F>
double chunked(long n, F&& f) {
  double total = 0;
  for (long lo = 0; lo < n; lo += reduce_chunk) {
    double s = 0;
    for (long i = lo; i < std::min(n, lo + reduce_chunk); ++i) s += f(i);
    total += s;
  }
  return total;
}
}  // namespace

TEST(Kernels, SumsAreTheSameBitsForAnyThreadCount) {
  // 27,000 rows (7 chunks) whose non-zeros per row grow with the row: SpMV's row blocks of equal
  // non-zeros then fall far from the chunk boundaries, which spmv_dot must cut them on.
  const SparseMatrix P = xb::test::poisson3d(30);
  const long n = P.rows();
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    for (SparseMatrix::InnerIterator it(P, i); it; ++it) t.emplace_back(i, it.col(), it.value());
    for (int c = 0; c < i / 3000; ++c) t.emplace_back(i, (i + 101 * c + 1) % n, 1e-3 * (c + 1));
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  const Vector x = xb::test::random_vector(n, 3), p = xb::test::random_vector(n, 4), r0 = xb::test::random_vector(n, 5);
  const Vector Ax = A * x;
  const double want_xy = chunked(n, [&](long i) { return x[i] * Ax[i]; });
  const double want_dot = chunked(n, [&](long i) { return x[i] * p[i]; });
  const Vector r_new = r0 - 0.7 * Ax;
  const double want_rr = chunked(n, [&](long i) { return r_new[i] * r_new[i]; });
  const int saved = omp_get_max_threads();
  for (int t : {1, 2, 3, 4, 7}) {
    omp_set_num_threads(t);
    Vector y, xx = p, rr = r0;
    EXPECT_TRUE(same_bits(spmv_dot(A, x, y), want_xy)) << t << " threads";
    EXPECT_TRUE(same_bits(dot(x, p), want_dot)) << t << " threads";
    EXPECT_TRUE(same_bits(cg_update(0.7, x, Ax, xx, rr), want_rr)) << t << " threads";
  }
  omp_set_num_threads(saved);
}
