// The smoothed prolongator (smoothed_prolongator.hpp) against a dense Jacobi step.
#include "core/error.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/smoothed_prolongator.hpp"
#include "solvers/amg/tentative.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

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
