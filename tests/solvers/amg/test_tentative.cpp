// The tentative prolongator (tentative.hpp): orthonormal per aggregate, reproducing the
// candidates (ones on the dual form, the rigid modes on K).
#include "core/error.hpp"
#include "solvers/amg/aggregation.hpp"
#include "solvers/amg/near_kernel.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/strength.hpp"
#include "solvers/amg/tentative.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgTentative, OrthonormalPerAggregateAndReproducesCandidates) {
  SceneSystem s = scene_system("cloth_hang", 12, 0);
  const SparseMatrix& A = s.ds->A();
  NearKernelOptions nk;
  nk.kind = "gs";
  nk.sweeps = 5;
  nk.vectors = 3;
  nk.seed = 3;
  const Eigen::MatrixXd B = near_kernel_candidates(A, nk);
  ASSERT_EQ(B.cols(), 3);
  // Seeded: the same candidates again.
  EXPECT_EQ((B - near_kernel_candidates(A, nk)).norm(), 0.0);
  const Aggregates agg = standard_aggregation(strength_symmetric(A, 0.25));
  const Tentative T = tentative_prolongator(agg, B);
  const Eigen::MatrixXd P(T.P);
  // Columns of one aggregate are orthonormal and columns of different aggregates have disjoint
  // supports: PᵀP = I exactly when both hold.
  const Eigen::MatrixXd PtP = P.transpose() * P;
  EXPECT_LE((PtP - Eigen::MatrixXd::Identity(PtP.rows(), PtP.cols())).cwiseAbs().maxCoeff(), 1e-12);
  for (int i = 0; i < P.rows(); ++i)
    for (int c = 0; c < P.cols(); ++c)
      if (P(i, c) != 0) {
        const int a = agg.aggregate[i];
        EXPECT_TRUE(c >= T.col_start[a] && c < T.col_start[a + 1]);
      }
  EXPECT_GT(T.max_row_entries, 1);
  EXPECT_LE(rel_diff(P * T.B_coarse, B), 1e-12);
  EXPECT_LE((Eigen::MatrixXd(T.R) - P.transpose()).norm(), 0.0);
  // One candidate: one entry per row, and B = 1 is reproduced.
  const Tentative T1 = tentative_prolongator(agg, Eigen::MatrixXd::Ones(A.rows(), 1));
  EXPECT_EQ(T1.max_row_entries, 1);
  EXPECT_LE(rel_diff(Eigen::MatrixXd(T1.P) * T1.B_coarse, Eigen::MatrixXd::Ones(A.rows(), 1)), 1e-12);
}

// P·B_c = B to round-off for the 6 rigid modes on the nodal aggregates; aggregates of one or two
// particles keep 3 or 5 columns (the rank of the rigid modes there), all others 6.
TEST(AmgBlockTentative, ReproducesTheRigidModes) {
  for (const auto* c : {&small_bar(), &small_cloth()}) {
    const SparseMatrix& K = c->K;
    const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
    const Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
    const Tentative T = tentative_prolongator(agg, c->rigid);
    EXPECT_LE(rel_diff(Dense(T.P * T.B_coarse), c->rigid), 1e-12);
    EXPECT_LE((Dense(T.R * T.P) - Dense::Identity(T.P.cols(), T.P.cols())).norm(), 1e-12);
    int six = 0;
    std::vector<int> size(agg.num_aggregates, 0);
    for (int a : agg.aggregate)
      if (a >= 0) ++size[a];
    for (int a = 0; a < agg.num_aggregates; ++a) {
      const int cols = T.col_start[a + 1] - T.col_start[a];
      const int expect = size[a] == 3 ? 3 : size[a] == 6 ? 5 : 6;  // collinear triples are not expected
      if (size[a] <= 6) {
        EXPECT_EQ(cols, expect) << "aggregate of " << size[a] / 3 << " particles";
      }
      six += cols == 6;
    }
    EXPECT_GT(six, agg.num_aggregates / 2);
  }
}
