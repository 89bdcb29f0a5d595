// Standard aggregation (aggregation.hpp): a partition, deterministic.
#include "core/error.hpp"
#include "solvers/amg/aggregation.hpp"
#include "solvers/amg/strength.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgAggregation, StandardAggregationPartitionsAndIsDeterministic) {
  // 1D Laplacian: pass 1 takes roots 0, 3, 6, ... with both neighbours: aggregates of three.
  const int n = 10;
  SparseMatrix L(n, n);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2);
    if (i) t.emplace_back(i, i - 1, -1);
    if (i + 1 < n) t.emplace_back(i, i + 1, -1);
  }
  L.setFromTriplets(t.begin(), t.end());
  const Aggregates a = standard_aggregation(strength_symmetric(L, 0.25));
  // Roots 0 ({0,1}), 3 ({2,3,4}), 6 ({5,6,7}), 9 ({8,9}) in pass 1: row 0's aggregate is {0,1}.
  EXPECT_EQ(a.num_aggregates, 4);
  const std::vector<int> expect = {0, 0, 1, 1, 1, 2, 2, 2, 3, 3};
  EXPECT_EQ(a.aggregate, expect);

  SceneSystem s = scene_system("cloth_hang", 16, 0);
  const SparseMatrix S = strength_symmetric(s.ds->A(), 0.25);
  const Aggregates a1 = standard_aggregation(S), a2 = aggregation_rule("standard")(S);
  EXPECT_EQ(a1.aggregate, a2.aggregate);
  std::vector<int> size(a1.num_aggregates, 0);
  for (int i = 0; i < S.rows(); ++i) {
    ASSERT_GE(a1.aggregate[i], -1);
    ASSERT_LT(a1.aggregate[i], a1.num_aggregates);
    if (a1.aggregate[i] >= 0) ++size[a1.aggregate[i]];
  }
  for (int c : size) EXPECT_GT(c, 0);
  // Each root lies in its own aggregate; every aggregated row is the root or strongly connected
  // to a row of its aggregate (aggregates are connected in S).
  for (int g = 0; g < a1.num_aggregates; ++g) EXPECT_EQ(a1.aggregate[a1.roots[g]], g);
  for (int i = 0; i < S.rows(); ++i) {
    if (a1.aggregate[i] < 0) continue;
    bool linked = a1.roots[a1.aggregate[i]] == i;
    for (SparseMatrix::InnerIterator it(S, i); it && !linked; ++it)
      linked = it.col() != i && a1.aggregate[it.col()] == a1.aggregate[i];
    EXPECT_TRUE(linked) << i;
  }
  EXPECT_THROW(aggregation_rule("nope"), Error);
}
