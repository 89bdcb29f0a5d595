// λ_max(D⁻¹A) by Lanczos (lanczos.hpp): an upper estimate within a few per cent of the dense
// eigenvalue, on Poisson and on a cloth's dual system.
#include "solvers/amg/relaxation/lanczos.hpp"
#include "solvers/kernels.hpp"

#include "../amg_test_support.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(Lanczos, EstimateBoundsTheLargestEigenvalueOfDinvA) {
  SceneSystem cloth = scene_system("cloth_hang", 8, 0);
  for (const SparseMatrix& A : {poisson2d(12), SparseMatrix(cloth.ds->A())}) {
    const Vector dinv = inverse_diagonal(A);
    // D^{-1/2} A D^{-1/2} has the eigenvalues of D⁻¹A and is symmetric.
    const Vector s = dinv.cwiseSqrt();
    const Eigen::MatrixXd S = s.asDiagonal() * Eigen::MatrixXd(A) * s.asDiagonal();
    const double exact = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S).eigenvalues().maxCoeff();
    Vector v;
    const double est = estimate_lambda_max(A, dinv, v, 20);
    EXPECT_GE(est, exact * (1 - 1e-10)) << A.rows();
    EXPECT_LE(est, exact * 1.05) << A.rows();
    EXPECT_EQ(v.size(), A.rows());  // the start of the next estimate
  }
}
