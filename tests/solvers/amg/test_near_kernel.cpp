// Near-kernel candidates (near_kernel.hpp): ones, relaxed random vectors that are smooth in A's
// energy, and the caller's basis passed through for rigid.
#include "solvers/amg/near_kernel.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

namespace {
// vᵀAv / vᵀv
double rayleigh(const SparseMatrix& A, const Vector& v) { return v.dot(A * v) / v.squaredNorm(); }
}  // namespace

TEST(NearKernel, OnesIsOneConstantColumn) {
  const SparseMatrix A = poisson2d(8);
  NearKernelOptions o;
  const Eigen::MatrixXd B = near_kernel_candidates(A, o);
  ASSERT_EQ(B.rows(), A.rows());
  ASSERT_EQ(B.cols(), 1);
  EXPECT_EQ(B.minCoeff(), B.maxCoeff());
}

// Gauss–Seidel on A x = 0 damps the high-energy components of a random start: the candidates'
// Rayleigh quotients fall far below a random vector's (about the mean eigenvalue, 4 here).
TEST(NearKernel, RelaxedRandomVectorsAreUnitAndSmooth) {
  const SparseMatrix A = poisson2d(20);
  const Eigen::MatrixXd V = relaxed_random_vectors(A, 3, 20, 7);
  ASSERT_EQ(V.cols(), 3);
  const double random_start = rayleigh(A, random_vector(A.rows(), 7));
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(V.col(k).norm(), 1.0, 1e-12);
    EXPECT_LT(rayleigh(A, V.col(k)), 0.1 * random_start) << k;
  }
}

TEST(NearKernel, RigidWithoutExtraReturnsTheGivenBasis) {
  const SparseMatrix A = poisson2d(6);
  const Eigen::MatrixXd given = Eigen::MatrixXd::Random(A.rows(), 2);
  NearKernelOptions o;
  o.kind = "rigid";
  EXPECT_EQ(near_kernel_candidates(A, o, nullptr, 1, &given), given);
}
