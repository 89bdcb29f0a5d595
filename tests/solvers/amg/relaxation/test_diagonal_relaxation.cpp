// The fused relaxation step (diagonal_relaxation.hpp) against its dense formula, with the scalar
// diagonal and with node blocks, and its float copy to single-precision round-off.
#include "solvers/amg/relaxation/diagonal_relaxation.hpp"
#include "solvers/kernels.hpp"

#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(DiagonalRelaxation, StepIsTheDenseFormula) {
  const SparseMatrix A = poisson2d(7);
  const Vector b = random_vector(A.rows(), 1), x = random_vector(A.rows(), 2), d0 = random_vector(A.rows(), 3);
  DiagonalRelaxation<double> r;
  r.inv_diag = inverse_diagonal(A);
  r.d = d0;
  r.step(A, b, x, 0.5, 0.3);
  const Vector ref = 0.5 * d0 + 0.3 * r.inv_diag.cwiseProduct(b - A * x);
  EXPECT_LE((r.d - ref).norm(), 1e-14 * ref.norm());
  // The same with 1×1 node blocks.
  DiagonalRelaxation<double> blocks;
  blocks.node_start.resize(A.rows() + 1);
  blocks.offset.resize(A.rows());
  for (int i = 0; i <= A.rows(); ++i) blocks.node_start[i] = i;
  for (int i = 0; i < A.rows(); ++i) blocks.offset[i] = i;
  blocks.block_inv.assign(r.inv_diag.data(), r.inv_diag.data() + A.rows());
  blocks.d = d0;
  blocks.step(A, b, x, 0.5, 0.3);
  EXPECT_LE((blocks.d - ref).norm(), 1e-14 * ref.norm());
}

TEST(DiagonalRelaxation, FloatCopySmoothsToSinglePrecision) {
  const SparseMatrix A = poisson2d(10);
  const Vector b = random_vector(A.rows(), 4);
  DiagonalRelaxation<double> r;
  r.inv_diag = inverse_diagonal(A);
  r.lambda = 2.0;  // D⁻¹A of 2D Poisson has λ_max < 2
  Vector x;
  r.presmooth(A, b, x = Vector::Zero(A.rows()), true);
  DiagonalRelaxation<float> f = to_single(r);
  const CsrOf<float> Af = A.cast<float>();
  VectorOf<float> xf = VectorOf<float>::Zero(A.rows());
  f.presmooth(Af, b.cast<float>(), xf, true);
  EXPECT_LE((xf.cast<double>() - x).norm(), 1e-5 * x.norm());
}
