// Nodal coarsening (nodal.hpp): the node matrix and aggregates that keep particles whole.
#include "core/error.hpp"
#include "solvers/amg/aggregation.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/strength.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgNodal, NodeMatrixIsTheBlockFrobeniusNorm) {
  const SparseMatrix& K = small_bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const SparseMatrix N = node_matrix(K, nodes);
  const Dense Kd(K);
  const int nn = nodes.num_nodes();
  Dense ref = Dense::Zero(nn, nn);
  for (int I = 0; I < nn; ++I)
    for (int J = 0; J < nn; ++J) ref(I, J) = Kd.block<3, 3>(3 * I, 3 * J).norm();
  EXPECT_LE(rel_diff(Dense(N), ref), 1e-14);
  EXPECT_THROW(NodeLayout::uniform(10, 3), Error);
  // From the node-block pattern (the hierarchy's path): the same pattern, the same values.
  BlockPattern p;
  ASSERT_TRUE(p.build(K, nodes, nodes));
  const SparseMatrix Nb = node_matrix(K, p);
  ASSERT_EQ(Nb.nonZeros(), N.nonZeros());
  for (int I = 0; I < nn; ++I)
    for (int k = N.outerIndexPtr()[I]; k < N.outerIndexPtr()[I + 1]; ++k) {
      ASSERT_EQ(Nb.outerIndexPtr()[I], N.outerIndexPtr()[I]);
      EXPECT_EQ(Nb.innerIndexPtr()[k], N.innerIndexPtr()[k]);
      EXPECT_EQ(Nb.valuePtr()[k], N.valuePtr()[k]);
    }
}

TEST(AmgNodal, AggregatesKeepParticlesWholeAndMatchScalarAggregationOfTheNodeGraph) {
  const SparseMatrix& K = small_cloth().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Aggregates agg = nodal_aggregation(K, nodes, 0.25, &standard_aggregation);
  const Aggregates node_agg = standard_aggregation(strength_symmetric(node_matrix(K, nodes), 0.25));
  ASSERT_EQ(agg.num_aggregates, node_agg.num_aggregates);
  ASSERT_GT(agg.num_aggregates, 0);
  for (int I = 0; I < nodes.num_nodes(); ++I)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(agg.aggregate[3 * I + d], node_agg.aggregate[I]);
}
