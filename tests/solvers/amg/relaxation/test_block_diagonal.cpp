// The node-block diagonal (block_diagonal.hpp): its inverse and Lanczos estimate against dense.
#include "core/error.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/relaxation/block_diagonal.hpp"

#include "../amg_test_support.hpp"
#include "../test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgBlockDiagonal, InverseAndLanczosAgainstDense) {
  const SparseMatrix& K = small_cloth().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  BlockDiagonal D;
  D.build(K, nodes);
  const Vector x = xb::test::random_vector(K.rows(), 4);
  Vector y, z;
  D.apply(x, y);
  D.apply_inverse(y, z);
  EXPECT_LE((z - x).norm(), 1e-12 * x.norm());
  SparseMatrix bad = K;
  bad.coeffRef(0, 0) = -1;
  EXPECT_THROW(D.build(bad, nodes), Error);
}
