// The smoothed prolongator (smoothed_prolongator.hpp) against a dense Jacobi step.
#include "core/error.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/smoothed_prolongator.hpp"
#include "solvers/amg/tentative.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

// P = (I − ωD⁻¹K)T against dense, ω = 4/(3λ_max(D⁻¹K)) with λ_max an upper estimate; P·B_c equals
// (I − ωD⁻¹K)B, which stays close to B because K's rigid modes are near its kernel.
TEST(AmgSmoothedProlongator, MatchesDenseJacobiStepForScalarAndBlockDiagonal) {
  const SparseMatrix& K = small_bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
  const Tentative T = tentative_prolongator(agg, small_bar().rigid);
  const Dense Kd(K);
  for (const JacobiDiagonal diag : {JacobiDiagonal::Scalar, JacobiDiagonal::Block}) {
    const SmoothedProlongator S = smooth_prolongator(K, T.P, diag, nodes, 20, 1);
    Dense Dinv = Dense::Zero(K.rows(), K.cols());
    for (int I = 0; I < nodes.num_nodes(); ++I) {
      if (diag == JacobiDiagonal::Block)
        Dinv.block<3, 3>(3 * I, 3 * I) = Kd.block<3, 3>(3 * I, 3 * I).inverse();
      else
        for (int d = 0; d < 3; ++d) Dinv(3 * I + d, 3 * I + d) = 1.0 / Kd(3 * I + d, 3 * I + d);
    }
    const Dense DK = Dinv * Kd;
    const double lmax = Eigen::EigenSolver<Dense>(DK).eigenvalues().real().maxCoeff();
    EXPECT_GE(S.lambda, lmax * (1 - 1e-8));
    EXPECT_LE(S.lambda, lmax * 1.1);
    EXPECT_NEAR(S.omega, 4.0 / (3.0 * S.lambda), 1e-15);
    const Dense Pref = (Dense::Identity(K.rows(), K.rows()) - S.omega * DK) * Dense(T.P);
    EXPECT_LE(rel_diff(Dense(S.P), Pref), 1e-13);
    EXPECT_LE(rel_diff(Dense(S.R), Pref.transpose()), 1e-13);
    EXPECT_LE(rel_diff(Dense(S.P * T.B_coarse), (Dense::Identity(K.rows(), K.rows()) - S.omega * DK) * small_bar().rigid), 1e-12);
  }
}

// drop_small_blocks against its definition on a smoothed P: a block (fine node × coarse node) is
// kept iff its Frobenius norm is ≥ tol · the largest of its fine node's, with its values; the
// rest are gone. tol = 0 drops nothing.
TEST(AmgSmoothedProlongator, DropSmallBlocksKeepsExactlyTheBlocksAboveTheTolerance) {
  const SparseMatrix& K = small_bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Tentative T = tentative_prolongator(nodal_aggregation(K, nodes, 0.0, &standard_aggregation), small_bar().rigid);
  const NodeLayout coarse{T.col_start};
  const SmoothedProlongator S = smooth_prolongator(K, T.P, JacobiDiagonal::Block, nodes, 20, 1, coarse);
  SparseMatrix P0 = S.P;
  EXPECT_EQ(drop_small_blocks(P0, nodes, coarse, 0.0), 0);
  EXPECT_EQ(P0.nonZeros(), S.P.nonZeros());
  const double tol = 0.2;
  SparseMatrix P = S.P;
  const long dropped = drop_small_blocks(P, nodes, coarse, tol);
  EXPECT_GT(dropped, 0);
  EXPECT_EQ(P.nonZeros() + dropped, S.P.nonZeros());
  const Dense full(S.P), kept(P);
  long expect_dropped = 0;
  for (int I = 0; I < nodes.num_nodes(); ++I) {
    std::vector<double> norm(coarse.num_nodes());
    for (int J = 0; J < coarse.num_nodes(); ++J)
      norm[J] = full.block(3 * I, coarse.node_start[J], 3, coarse.node_start[J + 1] - coarse.node_start[J]).norm();
    const double big = *std::max_element(norm.begin(), norm.end());
    for (int J = 0; J < coarse.num_nodes(); ++J) {
      const int c0 = coarse.node_start[J], w = coarse.node_start[J + 1] - c0;
      const bool stored = [&] {  // a block of S.P's pattern (a stored block may hold zeros)
        for (SparseMatrix::InnerIterator it(S.P, 3 * I); it; ++it)
          if (it.col() == c0) return true;
        return false;
      }();
      if (!stored) continue;
      if (norm[J] >= tol * big) {
        EXPECT_EQ((kept.block(3 * I, c0, 3, w) - full.block(3 * I, c0, 3, w)).norm(), 0) << I << " " << J;
      } else {
        EXPECT_EQ(kept.block(3 * I, c0, 3, w).norm(), 0) << I << " " << J;
        expect_dropped += 3 * w;
      }
    }
  }
  EXPECT_EQ(dropped, expect_dropped);
  // A scalar layout drops entries: the same rule per row.
  SparseMatrix Ps = S.P;
  const long dropped_entries = drop_small_blocks(Ps, {}, {}, tol);
  EXPECT_GT(dropped_entries, 0);
  for (int i = 0; i < Ps.rows(); ++i) {
    const double big = Dense(S.P.row(i)).cwiseAbs().maxCoeff();
    for (SparseMatrix::InnerIterator it(Ps, i); it; ++it) EXPECT_GE(std::abs(it.value()), tol * big);
    long large = 0;
    for (SparseMatrix::InnerIterator it(S.P, i); it; ++it) large += std::abs(it.value()) >= tol * big;
    EXPECT_EQ(Ps.row(i).nonZeros(), large) << i;
  }
}
