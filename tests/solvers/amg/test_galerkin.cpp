// The Galerkin products (galerkin.hpp) against general sparse and dense products, and a refresh
// against a fresh product.
#include "core/error.hpp"
#include "solvers/amg/aggregation.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/smoothed_prolongator.hpp"
#include "solvers/amg/strength.hpp"
#include "solvers/amg/tentative.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgGalerkin, AggregateSumEqualsGeneralAndDenseProducts) {
  SceneSystem s = scene_system("bar_hang", 3, 0);
  const SparseMatrix& A = s.ds->A();
  const Aggregates agg = standard_aggregation(strength_symmetric(A, 0.1));
  // Non-constant candidate so that the weights p_i p_j matter.
  Eigen::MatrixXd B = Eigen::MatrixXd::Ones(A.rows(), 1) + 0.5 * random_vector(A.rows(), 5);
  const Tentative T = tentative_prolongator(agg, B);
  const Eigen::MatrixXd P(T.P), Ad(A);
  const Eigen::MatrixXd ref = P.transpose() * Ad * P;
  SparseMatrix Ac_fast;
  AggregateGalerkin g;
  g.build(A, T.P, T.R, Ac_fast);
  const SparseMatrix Ac_gen = galerkin_product(T.R, A, T.P);
  EXPECT_LE(rel_diff(Eigen::MatrixXd(Ac_fast), ref), 1e-12);
  EXPECT_LE(rel_diff(Eigen::MatrixXd(Ac_gen), ref), 1e-12);
  EXPECT_EQ(Ac_fast.nonZeros(), Ac_gen.nonZeros());
  // Values-only refresh after A changes (same pattern).
  SparseMatrix A2 = A;
  Vector scale = random_vector(A.rows(), 9).array() + 2.0;
  A2 = scale.asDiagonal() * A * scale.asDiagonal();
  g.refresh(A2, Ac_fast);
  const Eigen::MatrixXd ref2 = P.transpose() * Eigen::MatrixXd(A2) * P;
  EXPECT_LE(rel_diff(Eigen::MatrixXd(Ac_fast), ref2), 1e-12);
  // Several candidates: the general product against dense; the aggregate path refuses.
  B.conservativeResize(Eigen::NoChange, 2);
  B.col(1) = random_vector(A.rows(), 11);
  const Tentative T2 = tentative_prolongator(agg, B);
  const Eigen::MatrixXd P2(T2.P);
  EXPECT_LE(rel_diff(Eigen::MatrixXd(galerkin_product(T2.R, A, T2.P)), P2.transpose() * Ad * P2), 1e-12);
  AggregateGalerkin g2;
  SparseMatrix dummy;
  EXPECT_THROW(g2.build(A, T2.P, T2.R, dummy), Error);
}

// The cached Galerkin product is bit-identical to a fresh one, for new values on the same pattern.
TEST(AmgGalerkinProduct, RefreshEqualsAFreshProduct) {
  const SparseMatrix K1 = small_bar().K;
  SparseMatrix K2 = K1;
  const Vector noise = xb::test::random_vector(K2.nonZeros(), 9);
  for (long k = 0; k < K2.nonZeros(); ++k) K2.valuePtr()[k] *= 1.0 + 0.1 * noise[k];
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K1.rows()), 3);
  const Tentative T = tentative_prolongator(nodal_aggregation(K1, nodes, 0.0, &standard_aggregation), small_bar().rigid);
  const SmoothedProlongator S = smooth_prolongator(K1, T.P, JacobiDiagonal::Scalar, nodes, 20, 1);
  GalerkinProduct g;
  SparseMatrix Ac;
  g.build(S.R, K1, S.P, Ac);
  EXPECT_LE(rel_diff(Dense(Ac), Dense(S.P).transpose() * Dense(K1) * Dense(S.P)), 1e-13);
  g.refresh(S.R, K2, S.P, Ac);
  const SparseMatrix fresh = galerkin_product(S.R, K2, S.P);
  ASSERT_EQ(Ac.nonZeros(), fresh.nonZeros());
  for (long k = 0; k < Ac.nonZeros(); ++k) ASSERT_EQ(Ac.valuePtr()[k], fresh.valuePtr()[k]);
}
