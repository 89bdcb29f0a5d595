// The node-block products of block levels (block_sparse.hpp) against the scalar CSR products on
// real primal-form systems: K·T, the smoothed P, the Galerkin product and its refresh,
// on level 0 (3×3 blocks) and on a coarse level whose nodes have 3, 5 or 6 unknowns.
#include "core/error.hpp"
#include "solvers/amg/block_sparse.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/smoothed_prolongator.hpp"
#include "test_amg_primal.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using xb::test::primal_case;

namespace {
using Dense = Eigen::MatrixXd;

const xb::test::PrimalCase& bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  return c;
}

// Same pattern (the block path stores no zero the scalar product does not) and values to 1e-13.
void expect_same(const SparseMatrix& block, const SparseMatrix& scalar, const std::string& what) {
  ASSERT_EQ(block.rows(), scalar.rows()) << what;
  ASSERT_EQ(block.cols(), scalar.cols()) << what;
  ASSERT_EQ(block.nonZeros(), scalar.nonZeros()) << what;
  for (long i = 0; i <= block.rows(); ++i) ASSERT_EQ(block.outerIndexPtr()[i], scalar.outerIndexPtr()[i]) << what;
  for (long k = 0; k < block.nonZeros(); ++k) ASSERT_EQ(block.innerIndexPtr()[k], scalar.innerIndexPtr()[k]) << what;
  const Eigen::Map<const Vector> bv(block.valuePtr(), block.nonZeros()), sv(scalar.valuePtr(), scalar.nonZeros());
  EXPECT_LE((bv - sv).norm(), 1e-13 * sv.norm()) << what;
  EXPECT_GT(sv.norm(), 0) << what;
}

// The nodal aggregates of K with the first particle of aggregate 0 moved to an aggregate of its
// own: its QR keeps 3 of the 6 rigid modes, so the coarse nodes have unequal sizes.
Tentative tentative_with_small_aggregate(const SparseMatrix& K, const NodeLayout& nodes, const Dense& rigid) {
  Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
  const int first = static_cast<int>(std::find(agg.aggregate.begin(), agg.aggregate.end(), 0) - agg.aggregate.begin());
  for (int d = 0; d < 3; ++d) agg.aggregate[first + d] = agg.num_aggregates;
  agg.roots.push_back(first);
  ++agg.num_aggregates;
  return tentative_prolongator(agg, rigid);
}

// Coarse layouts with nodes of fewer than 6 columns (the QR kept fewer rigid modes there).
int small_nodes(const std::vector<int>& start) {
  int small = 0;
  for (size_t a = 0; a + 1 < start.size(); ++a) small += start[a + 1] - start[a] < 6;
  return small;
}
}  // namespace

TEST(AmgBlockSparse, PatternOfKAndWhatIsNotBlocks) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  BlockPattern p;
  ASSERT_TRUE(p.build(K, nodes, nodes));
  EXPECT_EQ(p.ptr.back() * 9, K.nonZeros());  // K's node blocks are stored whole
  EXPECT_FALSE(p.build(K, NodeLayout{}, nodes));
  NodeLayout shifted;  // nodes of 1, 3, …, 3, 2 columns: each cuts through K's blocks
  shifted.node_start = {0};
  for (int s = 1; s < K.cols(); s += 3) shifted.node_start.push_back(s);
  shifted.node_start.push_back(static_cast<int>(K.cols()));
  EXPECT_FALSE(p.build(K, nodes, shifted));
  SparseMatrix holed = K;
  holed.coeffRef(0, 1) = 0;
  holed.prune([](int i, int j, double) { return !(i == 0 && j == 1); });
  EXPECT_FALSE(p.build(holed, nodes, nodes));  // row 0 of node 0 lacks a column its other rows hold
}

TEST(AmgBlockSparse, ProductsEqualTheScalarOnesWithUnequalCoarseNodes) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Tentative T = tentative_with_small_aggregate(K, nodes, bar().rigid);
  const NodeLayout coarse{T.col_start};
  ASSERT_GT(small_nodes(T.col_start), 0);
  BlockPattern pk, pt, pkt;
  ASSERT_TRUE(pk.build(K, nodes, nodes));
  ASSERT_TRUE(pt.build(T.P, nodes, coarse));
  const SparseMatrix KT = block_product(K, pk, T.P, pt, pkt);
  expect_same(KT, spgemm(K, T.P), "K T");
  // The Galerkin product of T, then of the smoothed P, for both Jacobi diagonals.
  GalerkinProduct g;
  SparseMatrix Ac;
  g.build(T.R, K, T.P, Ac, nodes, coarse);
  EXPECT_TRUE(g.by_blocks());
  expect_same(Ac, galerkin_product(T.R, K, T.P), "T^T K T");
  for (const JacobiDiagonal diag : {JacobiDiagonal::Scalar, JacobiDiagonal::Block}) {
    const SmoothedProlongator S = smooth_prolongator(K, T.P, diag, nodes, 20, 1, coarse);
    const SmoothedProlongator ref = smooth_prolongator(K, T.P, diag, nodes, 20, 1);  // no coarse layout: scalar
    expect_same(S.P, ref.P, "smoothed P");
    expect_same(S.R, ref.R, "R = P^T");
    g.build(S.R, K, S.P, Ac, nodes, coarse);
    EXPECT_TRUE(g.by_blocks());
    expect_same(Ac, galerkin_product(ref.R, K, ref.P), "P^T K P");
    // A_c's blocks by the coarse layout, then the next level's product with unequal nodes.
    BlockPattern pc;
    EXPECT_TRUE(pc.build(Ac, coarse, coarse));
    const Tentative T1 = tentative_prolongator(nodal_aggregation(Ac, coarse, 0.0, &standard_aggregation), T.B_coarse);
    GalerkinProduct g1;
    SparseMatrix Ac1;
    g1.build(T1.R, Ac, T1.P, Ac1, coarse, NodeLayout{T1.col_start});
    EXPECT_TRUE(g1.by_blocks());
    expect_same(Ac1, galerkin_product(T1.R, Ac, T1.P), "level 1 Galerkin");
  }
}

// Refresh with new values of K equals a fresh block build and the scalar product.
TEST(AmgBlockSparse, RefreshEqualsAFreshProduct) {
  const SparseMatrix& K1 = bar().K;
  SparseMatrix K2 = K1;
  const Vector noise = xb::test::random_vector(K2.nonZeros(), 9);
  for (long k = 0; k < K2.nonZeros(); ++k) K2.valuePtr()[k] *= 1.0 + 0.1 * noise[k];
  K2 = SparseMatrix(0.5 * (K2 + SparseMatrix(K2.transpose())));
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K1.rows()), 3);
  const Tentative T = tentative_with_small_aggregate(K1, nodes, bar().rigid);
  const NodeLayout coarse{T.col_start};
  const SmoothedProlongator S = smooth_prolongator(K1, T.P, JacobiDiagonal::Scalar, nodes, 20, 1, coarse);
  GalerkinProduct g, fresh;
  SparseMatrix Ac, Ac_fresh;
  g.build(S.R, K1, S.P, Ac, nodes, coarse);
  ASSERT_EQ(K2.nonZeros(), K1.nonZeros());
  g.refresh(S.R, K2, S.P, Ac);
  fresh.build(S.R, K2, S.P, Ac_fresh, nodes, coarse);
  ASSERT_TRUE(g.by_blocks());
  expect_same(Ac, Ac_fresh, "refresh vs fresh block build");
  for (long k = 0; k < Ac.nonZeros(); ++k) ASSERT_EQ(Ac.valuePtr()[k], Ac_fresh.valuePtr()[k]);
  expect_same(Ac, galerkin_product(S.R, K2, S.P), "refresh vs scalar");
}

// The symmetric Galerkin product (blocks on and above the diagonal, the rest mirrored: the
// hierarchy's) equals the full one to round-off, is exactly symmetric, and its refresh equals a
// fresh symmetric build bit for bit; unequal coarse nodes (3 and 6 columns) included.
TEST(AmgBlockSparse, SymmetricGalerkinProductMirrorsTheUpperBlocks) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Tentative T = tentative_with_small_aggregate(K, nodes, bar().rigid);
  const NodeLayout coarse{T.col_start};
  const SmoothedProlongator S = smooth_prolongator(K, T.P, JacobiDiagonal::Block, nodes, 20, 1, coarse);
  BlockPattern pr, pk, pp;
  ASSERT_TRUE(pr.build(S.R, coarse, nodes) && pk.build(K, nodes, nodes) && pp.build(S.P, nodes, coarse));
  GalerkinProduct g;
  SparseMatrix Ac;
  g.build(S.R, K, S.P, Ac, pr, pk, pp, true);
  expect_same(Ac, galerkin_product(S.R, K, S.P), "symmetric P^T K P");
  const SparseMatrix AcT = SparseMatrix(Ac.transpose());
  ASSERT_EQ(AcT.nonZeros(), Ac.nonZeros());
  for (long k = 0; k < Ac.nonZeros(); ++k) ASSERT_EQ(Ac.valuePtr()[k], AcT.valuePtr()[k]) << "not exactly symmetric at " << k;
  SparseMatrix K2 = K;
  const Vector noise = xb::test::random_vector(K2.nonZeros(), 4);
  for (long k = 0; k < K2.nonZeros(); ++k) K2.valuePtr()[k] *= 1.0 + 0.1 * noise[k];
  K2 = SparseMatrix(0.5 * (K2 + SparseMatrix(K2.transpose())));
  ASSERT_EQ(K2.nonZeros(), K.nonZeros());
  g.refresh(S.R, K2, S.P, Ac);
  GalerkinProduct fresh;
  SparseMatrix Ac2;
  fresh.build(S.R, K2, S.P, Ac2, pr, pk, pp, true);
  for (long k = 0; k < Ac.nonZeros(); ++k) ASSERT_EQ(Ac.valuePtr()[k], Ac2.valuePtr()[k]);
  expect_same(Ac, galerkin_product(S.R, K2, S.P), "symmetric refresh");
  // A pattern without a mirror block, or not square, is refused.
  BlockPattern one_sided;  // blocks (0, 0), (1, 0), (1, 1): (1, 0) has no (0, 1)
  one_sided.row_start = one_sided.col_start = {0, 3, 6};
  one_sided.ptr = {0, 1, 3};
  one_sided.col = {0, 0, 1};
  one_sided.offset = {0, 0, 3};
  EXPECT_THROW(block_mirror_map(one_sided), Error);
  one_sided.col = {0, 1, 1};  // (0, 0), (1, 1), (1, 1)... as (1, 1) twice: no block below the diagonal
  EXPECT_EQ(block_mirror_map(one_sided), (std::vector<int>{-1, -1, -1}));
  EXPECT_THROW(block_mirror_map(pp), Error);  // P: rows and columns are different nodes
}

// Every level of a primal hierarchy (block products throughout) equals the scalar products of
// that level's R, A and P, and the coarse layouts have nodes of fewer than 6 unknowns.
TEST(AmgBlockSparse, HierarchyLevelsEqualTheScalarGalerkinProducts) {
  const auto c = primal_case("cloth_hang", {{"resolution", "24"}}, 3, 0);
  Hierarchy h;
  AmgOptions opt;
  opt.max_coarse = 50;
  opt.near_kernel.kind = "ones";  // coarse nodes of 3 columns (< 6: what small_nodes counts)
  MatrixInfo info;
  info.block_size = 3;
  info.near_kernel = &c.rigid;
  h.setup(c.K, opt, info);
  ASSERT_GE(h.num_levels(), 3);
  int small = 0;
  for (int l = 0; l + 1 < h.num_levels(); ++l) {
    const Level& L = h.level(l);
    EXPECT_TRUE(L.product.by_blocks()) << "level " << l;
    expect_same(h.matrix(l + 1), galerkin_product(L.T.R, h.matrix(l), L.T.P), "level " + std::to_string(l + 1));
    expect_same(L.T.R, transpose(L.T.P), "R level " + std::to_string(l));
    small += small_nodes(h.level(l + 1).nodes.node_start);
  }
  EXPECT_GT(small, 0);
}

// R = Pᵀ by the parallel counting sort equals Eigen's transpose exactly (pattern, sorted columns,
// values), on the bar's smoothed P and on a wide random matrix with empty rows and columns.
TEST(AmgBlockSparse, TransposeEqualsEigensExactly) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  const Tentative T = tentative_with_small_aggregate(K, nodes, bar().rigid);
  const SparseMatrix P = smooth_prolongator(K, T.P, JacobiDiagonal::Block, nodes, 20, 1).P;
  std::vector<Eigen::Triplet<double>> trip;
  const Vector r = xb::test::random_vector(30000, 11);
  for (int k = 0; k < 10000; ++k) {
    const int i = static_cast<int>(std::abs(r[3 * k]) * 4999), j = static_cast<int>(std::abs(r[3 * k + 1]) * 2999);
    if (i % 7 != 3 && j % 5 != 2) trip.emplace_back(i, j, r[3 * k + 2]);  // empty rows and columns
  }
  SparseMatrix Wm(5000, 3000);
  Wm.setFromTriplets(trip.begin(), trip.end());
  const SparseMatrix& W = Wm;
  for (const SparseMatrix* A : {&P, &W}) {
    const SparseMatrix mine = transpose(*A), eigen = SparseMatrix(A->transpose());
    ASSERT_EQ(mine.nonZeros(), eigen.nonZeros());
    for (long i = 0; i <= mine.rows(); ++i) ASSERT_EQ(mine.outerIndexPtr()[i], eigen.outerIndexPtr()[i]);
    for (long k = 0; k < mine.nonZeros(); ++k) {
      ASSERT_EQ(mine.innerIndexPtr()[k], eigen.innerIndexPtr()[k]);
      ASSERT_EQ(mine.valuePtr()[k], eigen.valuePtr()[k]);
    }
  }
}
