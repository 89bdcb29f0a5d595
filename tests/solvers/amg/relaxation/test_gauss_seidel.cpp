// Multicolour Gauss–Seidel (gauss_seidel.hpp) against a dense sequential sweep in the colouring's
// order, and the gs smoother converging as a solver.
#include "solvers/amg/relaxation/gauss_seidel.hpp"
#include "solvers/kernels.hpp"

#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(GaussSeidel, SweepEqualsDenseSequentialSweepInColourOrder) {
  const SparseMatrix A = poisson2d(9);
  const Eigen::MatrixXd Ad(A);
  const Coloring col = greedy_coloring(A);
  const Vector b = random_vector(A.rows(), 3), x0 = random_vector(A.rows(), 4);
  for (bool forward : {true, false}) {
    Vector ref = x0;
    for (int cc = 0; cc < col.num_colors; ++cc) {
      const int c = forward ? cc : col.num_colors - 1 - cc;
      for (int t = col.color_start[c]; t < col.color_start[c + 1]; ++t) {
        const int i = col.order[t];
        ref[i] += (b[i] - Ad.row(i).dot(ref)) / Ad(i, i);
      }
    }
    Vector x = x0;
    multicolor_gs_sweep(A, inverse_diagonal(A), col, b, x, forward);
    EXPECT_LE((x - ref).norm(), 1e-13 * ref.norm()) << forward;
  }
}

TEST(GaussSeidel, SmootherSweepsConvergeToTheSolution) {
  const SparseMatrix A = poisson2d(6);
  const Vector b = random_vector(A.rows(), 5);
  SmootherOptions o;
  o.kind = "gs";
  o.sweeps = 200;
  GaussSeidelSmoother gs(o, A);
  Vector x;
  gs.presmooth(A, b, x = Vector::Zero(A.rows()), true);
  Vector r;
  residual(A, x, b, r);
  EXPECT_LE(r.norm(), 1e-10 * b.norm());
}
