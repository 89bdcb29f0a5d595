// The block jacobi and chebyshev smoothers (block_chebyshev.hpp): one block-Jacobi sweep from zero
// is x = D⁻¹b/λ_max with D the dense node blocks; both kinds reduce the error of A x = b.
#include "solvers/amg/relaxation/block_chebyshev.hpp"
#include "solvers/kernels.hpp"

#include "../amg_test_support.hpp"
#include "../test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(BlockChebyshev, BlockJacobiSweepIsTheDenseBlockInverse) {
  const SparseMatrix& K = small_cloth().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Eigen::MatrixXd Kd(K);
  const Vector b = random_vector(K.rows(), 2);
  SmootherOptions o;
  o.kind = "block_jacobi";
  auto sm = make_block_diagonal_smoother(o, K, nodes, nullptr);
  Vector x = Vector::Zero(K.rows());
  sm->presmooth(K, b, x, true);
  Vector ref(K.rows());
  for (int I = 0; I < nodes.num_nodes(); ++I)
    ref.segment<3>(3 * I) = Kd.block<3, 3>(3 * I, 3 * I).inverse() * b.segment<3>(3 * I) / sm->lambda_max();
  EXPECT_LE((x - ref).norm(), 1e-12 * ref.norm());
}

TEST(BlockChebyshev, BothKindsReduceTheError) {
  const SparseMatrix& K = small_bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Vector x_true = random_vector(K.rows(), 3), b = K * x_true;
  for (const std::string kind : {"block_jacobi", "block_chebyshev"}) {
    SmootherOptions o;
    o.kind = kind;
    o.sweeps = 3;
    auto sm = make_block_diagonal_smoother(o, K, nodes, nullptr);
    Vector x = Vector::Zero(K.rows());
    sm->presmooth(K, b, x, true);
    // in the energy norm, which every sweep of an SPD polynomial smoother reduces
    const Vector e = x - x_true;
    EXPECT_LT(e.dot(K * e), x_true.dot(K * x_true)) << kind;
  }
}
