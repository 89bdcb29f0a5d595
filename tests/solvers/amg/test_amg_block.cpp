// The in-house AMG on block systems (the primal form's K): nodal strength and aggregation, the
// rigid-mode tentative prolongator, the smoothed prolongator, the cached Galerkin product and the
// block V-cycle, against dense computations.
#include "solvers/amg/relaxation/block_diagonal.hpp"
#include "solvers/amg/block_sparse.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/nodal.hpp"
#include "solvers/amg/smoothed_prolongator.hpp"
#include "solvers/amg/strength.hpp"
#include "core/error.hpp"
#include "test_amg_primal.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;
using namespace xb::amg;
using xb::test::primal_case;

namespace {
using Dense = Eigen::MatrixXd;

double rel(const Dense& a, const Dense& b) { return (a - b).norm() / b.norm(); }

// A small bar (stretched ARAP tets, one end pinned) and a small sagging cloth.
const xb::test::PrimalCase& bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  return c;
}
const xb::test::PrimalCase& cloth() {
  static const auto c = primal_case("cloth_hang", {{"resolution", "12"}}, 3, 0);
  return c;
}
}  // namespace

TEST(AmgNodal, NodeMatrixIsTheBlockFrobeniusNorm) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const SparseMatrix N = node_matrix(K, nodes);
  const Dense Kd(K);
  const int nn = nodes.num_nodes();
  Dense ref = Dense::Zero(nn, nn);
  for (int I = 0; I < nn; ++I)
    for (int J = 0; J < nn; ++J) ref(I, J) = Kd.block<3, 3>(3 * I, 3 * J).norm();
  EXPECT_LE(rel(Dense(N), ref), 1e-14);
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
  const SparseMatrix& K = cloth().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Aggregates agg = nodal_aggregation(K, nodes, 0.25, &standard_aggregation);
  const Aggregates node_agg = standard_aggregation(strength_symmetric(node_matrix(K, nodes), 0.25));
  ASSERT_EQ(agg.num_aggregates, node_agg.num_aggregates);
  ASSERT_GT(agg.num_aggregates, 0);
  for (int I = 0; I < nodes.num_nodes(); ++I)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(agg.aggregate[3 * I + d], node_agg.aggregate[I]);
}

// P·B_c = B to round-off for the 6 rigid modes on the nodal aggregates; aggregates of one or two
// particles keep 3 or 5 columns (the rank of the rigid modes there), all others 6.
TEST(AmgBlockTentative, ReproducesTheRigidModes) {
  for (const auto* c : {&bar(), &cloth()}) {
    const SparseMatrix& K = c->K;
    const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
    const Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
    const Tentative T = tentative_prolongator(agg, c->rigid);
    EXPECT_LE(rel(Dense(T.P * T.B_coarse), c->rigid), 1e-12);
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

// P = (I − ωD⁻¹K)T against dense, ω = 4/(3λ_max(D⁻¹K)) with λ_max an upper estimate; P·B_c equals
// (I − ωD⁻¹K)B, which stays close to B because K's rigid modes are near its kernel.
TEST(AmgSmoothedProlongator, MatchesDenseJacobiStepForScalarAndBlockDiagonal) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
  const Tentative T = tentative_prolongator(agg, bar().rigid);
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
    EXPECT_LE(rel(Dense(S.P), Pref), 1e-13);
    EXPECT_LE(rel(Dense(S.R), Pref.transpose()), 1e-13);
    EXPECT_LE(rel(Dense(S.P * T.B_coarse), (Dense::Identity(K.rows(), K.rows()) - S.omega * DK) * bar().rigid), 1e-12);
  }
}

TEST(AmgBlockDiagonal, InverseAndLanczosAgainstDense) {
  const SparseMatrix& K = cloth().K;
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

// The cached Galerkin product is bit-identical to a fresh one, for new values on the same pattern.
TEST(AmgGalerkinProduct, RefreshEqualsAFreshProduct) {
  const SparseMatrix K1 = bar().K;
  SparseMatrix K2 = K1;
  const Vector noise = xb::test::random_vector(K2.nonZeros(), 9);
  for (long k = 0; k < K2.nonZeros(); ++k) K2.valuePtr()[k] *= 1.0 + 0.1 * noise[k];
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K1.rows()), 3);
  const Tentative T = tentative_prolongator(nodal_aggregation(K1, nodes, 0.0, &standard_aggregation), bar().rigid);
  const SmoothedProlongator S = smooth_prolongator(K1, T.P, JacobiDiagonal::Scalar, nodes, 20, 1);
  GalerkinProduct g;
  SparseMatrix Ac;
  g.build(S.R, K1, S.P, Ac);
  EXPECT_LE(rel(Dense(Ac), Dense(S.P).transpose() * Dense(K1) * Dense(S.P)), 1e-13);
  g.refresh(S.R, K2, S.P, Ac);
  const SparseMatrix fresh = galerkin_product(S.R, K2, S.P);
  ASSERT_EQ(Ac.nonZeros(), fresh.nonZeros());
  for (long k = 0; k < Ac.nonZeros(); ++k) ASSERT_EQ(Ac.valuePtr()[k], fresh.valuePtr()[k]);
}

namespace {
// V is symmetric (xᵀV(y) = yᵀV(x)) and positive definite (xᵀV(x) > 0) on random vectors.
void check_spd(Hierarchy& h, const std::string& what) {
  const long n = h.matrix(0).rows();
  for (unsigned s = 0; s < 3; ++s) {
    const Vector x = xb::test::random_vector(n, 100 + s), y = xb::test::random_vector(n, 200 + s);
    Vector vx, vy;
    h.vcycle(x, vx);
    h.vcycle(y, vy);
    const double xy = x.dot(vy), yx = y.dot(vx);
    EXPECT_LE(std::abs(xy - yx), 1e-10 * std::sqrt(std::abs(x.dot(vx) * y.dot(vy)))) << what;
    EXPECT_GT(x.dot(vx), 0) << what;
    EXPECT_GT(y.dot(vy), 0) << what;
  }
}
}  // namespace

TEST(AmgBlockVcycle, SymmetricPositiveDefiniteForEverySmoother) {
  for (const auto* c : {&bar(), &cloth()})
    for (const std::string sm : {"jacobi", "chebyshev", "gs", "block_gs", "block_jacobi", "block_chebyshev"})
      for (const std::string pr : {"smoothed", "tentative"})
        for (const std::string diag : {"scalar", "block"}) {
          AmgOptions o;
          o.near_kernel.kind = "auto";
          o.prolongator = pr;
          o.prolongator_diagonal = diag;
          o.smoother.kind = sm;
          o.max_coarse = 30;
          Hierarchy h;
          h.setup(c->K, o, {3, &c->rigid});
          ASSERT_GE(h.num_levels(), 3);
          EXPECT_EQ(h.options().near_kernel.kind, "rigid");
          // Coarse levels are nodal: their nodes are the aggregates' kept columns (≤ 6 each).
          EXPECT_FALSE(h.level(1).nodes.scalar());
          EXPECT_EQ(h.level(1).nodes.node_start.back(), h.matrix(1).rows());
          check_spd(h, sm + "/" + pr + "/" + std::to_string(c->K.rows()));
        }
}

TEST(AmgBlockOptions, AutoResolvesByBlockSizeAndRigidNeedsABasis) {
  AmgOptions o;
  o.near_kernel.kind = "auto";
  Eigen::MatrixXd B(6, 6);
  EXPECT_EQ(resolve_options(o, {1, nullptr}).near_kernel.kind, "ones");
  EXPECT_EQ(resolve_options(o, {1, nullptr}).prolongator, "tentative");
  EXPECT_EQ(resolve_options(o, {3, nullptr}).near_kernel.kind, "ones");
  EXPECT_EQ(resolve_options(o, {3, nullptr}).prolongator, "smoothed");
  EXPECT_EQ(resolve_options(o, {3, &B}).near_kernel.kind, "rigid");
  o.near_kernel.kind = "rigid";
  EXPECT_THROW(resolve_options(o, {1, nullptr}), Error);
  o.prolongator = "energy";
  EXPECT_THROW(resolve_options(o, {}), Error);
}
