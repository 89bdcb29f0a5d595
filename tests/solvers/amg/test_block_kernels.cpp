// The V-cycle's node-block kernels (block_kernels.hpp) against Eigen's CSR products on real
// primal-form matrices: K (uniform 3×3 blocks, the unrolled path), a tentative P, R and coarse
// operator whose nodes have 3, 5 or 6 unknowns (the general path), in double and float; and a
// primal hierarchy hands every level's A, P and R to them. A V-cycle by node blocks is the one by
// plain CSR rows (same smoothers, same levels) to round-off, with the same PCG iterations.
#include "solvers/amg/block_kernels.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/relaxation/block_diagonal.hpp"
#include "solvers/krylov/pcg.hpp"
#include "test_amg_primal.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

#include <type_traits>

using namespace xb;
using namespace xb::amg;
using xb::test::primal_case;
using xb::test::random_vector;

namespace {
const xb::test::PrimalCase& bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  return c;
}

// The three kernels on A (row layout `rows`) against Eigen in precision S, to `tol` relative.
template <class S>
void expect_kernels_match(const SparseMatrix& A, const BlockOperator& op, const NodeLayout& rows, double tol,
                          const std::string& what) {
  using V = VectorOf<S>;
  const CsrOf<S> As = A.cast<S>();
  const V x = random_vector(A.cols(), 3).cast<S>(), b = random_vector(A.rows(), 4).cast<S>();
  const Vector Ax = A * x.template cast<double>();
  // y = A x, y += A x, r = b − A x.
  V y(A.rows());
  block_multiply(op, As, x.data(), y.data(), false);
  EXPECT_LE((y.template cast<double>() - Ax).norm(), tol * Ax.norm()) << what << ": A x";
  block_multiply(op, As, x.data(), y.data(), true);
  EXPECT_LE((y.template cast<double>() - 2 * Ax).norm(), tol * 2 * Ax.norm()) << what << ": y += A x";
  if (A.rows() != A.cols()) return;
  V r(A.rows());
  block_residual(op, As, x.data(), b.data(), r.data());
  const Vector r_ref = b.template cast<double>() - Ax;
  EXPECT_LE((r.template cast<double>() - r_ref).norm(), tol * r_ref.norm()) << what << ": b - A x";
  // d = c1 d + c2 M (b − A x) with a random row-major block M per node.
  const int nn = rows.num_nodes();
  std::vector<long> offset(nn + 1, 0);
  for (int I = 0; I < nn; ++I) {
    const long bi = rows.node_start[I + 1] - rows.node_start[I];
    offset[I + 1] = offset[I] + bi * bi;
  }
  const Vector m = random_vector(offset[nn], 5);
  const std::vector<S> M(m.data(), m.data() + m.size());
  const V d0 = random_vector(A.rows(), 6).cast<S>();
  const double c1 = 0.3, c2 = 1.7;
  V d = d0;
  block_relax_step(op, As, M.data(), offset.data(), b.data(), x.data(), c1, c2, d.data());
  Vector d_ref(A.rows());
  for (int I = 0; I < nn; ++I) {
    const int s = rows.node_start[I], bi = rows.node_start[I + 1] - s;
    for (int i = 0; i < bi; ++i) {
      double acc = 0;
      for (int j = 0; j < bi; ++j) acc += m[offset[I] + i * bi + j] * r_ref[s + j];
      d_ref[s + i] = c1 * d0[s + i] + c2 * acc;
    }
  }
  EXPECT_LE((d.template cast<double>() - d_ref).norm(), tol * d_ref.norm()) << what << ": relaxation step";
}

template <class S>
void expect_all_match(double tol) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  BlockOperator op;
  ASSERT_TRUE(op.build(K, nodes, nodes));
  EXPECT_EQ(op.uniform_rows, 3);
  EXPECT_EQ(op.uniform_cols, 3);
  expect_kernels_match<S>(K, op, nodes, tol, "K");
  {  // every aggregate with 6 columns: a uniform 6×6 Galerkin operator (the gathered SIMD path)
    const Tentative T6 = tentative_prolongator(nodal_aggregation(K, nodes, 0.0, &standard_aggregation), bar().rigid);
    const NodeLayout c6{T6.col_start};
    const SparseMatrix A6 = galerkin_product(T6.R, K, T6.P);
    BlockOperator op6;
    ASSERT_TRUE(op6.build(A6, c6, c6));
    ASSERT_EQ(op6.uniform_rows, 6);
    ASSERT_EQ(op6.uniform_cols, 6);
    expect_kernels_match<S>(A6, op6, c6, tol, "6x6 T^T K T");
  }
  // A tentative P whose first particle is an aggregate of its own (3 of the 6 rigid modes): the
  // coarse nodes have 3 and 6 unknowns, and the Galerkin operator's blocks are unequal too.
  Aggregates agg = nodal_aggregation(K, nodes, 0.0, &standard_aggregation);
  const int first = static_cast<int>(std::find(agg.aggregate.begin(), agg.aggregate.end(), 0) - agg.aggregate.begin());
  for (int d = 0; d < 3; ++d) agg.aggregate[first + d] = agg.num_aggregates;
  agg.roots.push_back(first);
  ++agg.num_aggregates;
  const Tentative T = tentative_prolongator(agg, bar().rigid);
  const NodeLayout coarse{T.col_start};
  BlockOperator p, r, ac;
  ASSERT_TRUE(p.build(T.P, nodes, coarse));
  ASSERT_TRUE(r.build(T.R, coarse, nodes));
  EXPECT_EQ(p.uniform_cols, 0);  // unequal coarse nodes: the general path
  expect_kernels_match<S>(T.P, p, nodes, tol, "P");
  expect_kernels_match<S>(T.R, r, coarse, tol, "R");
  const SparseMatrix Ac = galerkin_product(T.R, K, T.P);
  ASSERT_TRUE(ac.build(Ac, coarse, coarse));
  EXPECT_EQ(ac.uniform_rows, 0);
  expect_kernels_match<S>(Ac, ac, coarse, tol, "T^T K T");
}
}  // namespace

TEST(AmgBlockKernels, EqualEigenOnKAndOnUnequalCoarseNodes) { expect_all_match<double>(1e-13); }

TEST(AmgBlockKernels, FloatEqualsEigenToSinglePrecision) { expect_all_match<float>(1e-5); }

// Not node-block CSR (a row of a node lacks a column its other rows hold; a column layout
// cutting through the blocks): no block operator, and the V-cycle keeps the CSR kernels.
TEST(AmgBlockKernels, BuildRefusesWhatIsNotBlocks) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  SparseMatrix holed = K;
  holed.prune([](int i, int j, double) { return !(i == 0 && j == 1); });
  BlockOperator op;
  ASSERT_TRUE(op.build(K, nodes, nodes));
  EXPECT_FALSE(op.build(holed, nodes, nodes));
  EXPECT_TRUE(op.empty());
  NodeLayout shifted;  // nodes of 1, 3, …, 3, 2 columns: each cuts through K's blocks
  shifted.node_start = {0};
  for (int s = 1; s < K.cols(); s += 3) shifted.node_start.push_back(s);
  shifted.node_start.push_back(static_cast<int>(K.cols()));
  EXPECT_FALSE(op.build(K, nodes, shifted));
  EXPECT_TRUE(op.empty());
}

// Every level of a primal hierarchy but the coarsest (a direct solve) runs the block kernels for
// A, P and R; a dual (scalar) hierarchy runs none.
TEST(AmgBlockKernels, PrimalHierarchyLevelsHaveBlockOperators) {
  const auto c = primal_case("cloth_hang", {{"resolution", "24"}}, 3, 0);
  AmgOptions opt;
  opt.max_coarse = 50;
  MatrixInfo info;
  info.block_size = 3;
  info.near_kernel = &c.rigid;
  Hierarchy h;
  h.setup(c.K, opt, info);
  ASSERT_GE(h.num_levels(), 3);
  for (int l = 0; l < h.num_levels(); ++l) {
    const bool coarsest = l + 1 == h.num_levels();
    EXPECT_EQ(h.level(l).A_blocks == nullptr, coarsest) << "level " << l;
    EXPECT_EQ(h.level(l).P_blocks.empty(), coarsest) << "level " << l;
    EXPECT_EQ(h.level(l).R_blocks.empty(), coarsest) << "level " << l;
  }
  Hierarchy dual;
  dual.setup(c.A(), AmgOptions{});
  for (int l = 0; l < dual.num_levels(); ++l) EXPECT_EQ(dual.level(l).A_blocks, nullptr) << "dual level " << l;
}

// Lanczos reading K by blocks gives the scalar products' λ_max(D⁻¹K) estimate to round-off.
TEST(AmgBlockKernels, LanczosByBlocksEqualsTheScalarEstimate) {
  const SparseMatrix& K = bar().K;
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  BlockOperator op;
  ASSERT_TRUE(op.build(K, nodes, nodes));
  BlockDiagonal D;
  D.build(K, nodes);
  Vector v1, v2;
  const double scalar = estimate_lambda_max(K, D, v1, 20, 1);
  const double blocks = estimate_lambda_max(K, D, v2, 20, 1, &op);
  EXPECT_GT(scalar, 1.0);  // D⁻¹K has λ_max above 1 (its diagonal blocks are I)
  EXPECT_NEAR(blocks, scalar, 1e-10 * scalar);
  EXPECT_LE((v1 - v2).norm(), 1e-8 * v1.norm());
}

namespace {
// The V-cycle of h (Algorithm 2) by plain CSR rows in precision S: the same levels, the same
// polynomial smoothers with their block-operator pointer cleared (the node-by-node CSR path of
// diagonal_relaxation.cpp), Eigen's products for the residual, R and P, a dense coarse solve.
template <class S>
Vector csr_vcycle(const Hierarchy& h, const Vector& b) {
  using V = VectorOf<S>;
  const int nl = h.num_levels();
  const bool single = std::is_same_v<S, float>;
  std::vector<CsrOf<S>> A(nl), P(nl), R(nl);
  std::vector<DiagonalRelaxation<S>> relax(nl);
  for (int l = 0; l < nl; ++l) {
    A[l] = h.matrix(l).cast<S>();
    if (l + 1 == nl) break;
    P[l] = h.level(l).T.P.cast<S>();
    R[l] = h.level(l).T.R.cast<S>();
    if constexpr (std::is_same_v<S, float>) relax[l] = h.level(l).single.relax;
    else relax[l] = *h.level(l).smoother->relaxation();
    relax[l].blocks = nullptr;
  }
  const double scale = single ? b.cwiseAbs().maxCoeff() : 1.0;  // the float V-cycle runs on b/‖b‖∞
  std::vector<V> x(nl), rhs(nl);
  rhs[0] = (b / scale).cast<S>();
  for (int l = 0; l + 1 < nl; ++l) {
    relax[l].presmooth(A[l], rhs[l], x[l], true);
    rhs[l + 1] = R[l] * V(rhs[l] - A[l] * x[l]);
  }
  const Eigen::MatrixXd Ac(h.matrix(nl - 1));
  x[nl - 1] = Ac.llt().solve(rhs[nl - 1].template cast<double>()).template cast<S>();
  for (int l = nl - 2; l >= 0; --l) {
    x[l] += P[l] * x[l + 1];
    relax[l].postsmooth(A[l], rhs[l], x[l]);
  }
  return scale * x[0].template cast<double>();
}
}  // namespace

// Node-block storage gives the V-cycle of CSR storage: in double to 1e-12, in float (the default
// precision) to float round-off, and PCG to 1e-8 takes the same iterations with either.
TEST(AmgBlockKernels, BlockVcycleEqualsTheCsrVcycleAndItsPcgIterations) {
  const auto c = primal_case("cloth_hang", {{"resolution", "24"}}, 3, 0);
  for (const std::string precision : {"double", "single"}) {
    AmgOptions opt;
    opt.max_coarse = 50;
    opt.precision = precision;
    Hierarchy h;
    h.setup(c.K, opt, {3, &c.rigid});
    ASSERT_GE(h.num_levels(), 3);
    ASSERT_EQ(h.level(1).A_blocks->uniform_rows, 6);  // the rigid-mode level's 6×6 path runs
    const bool single = precision == "single";
    auto reference = [&](const Vector& r) { return single ? csr_vcycle<float>(h, r) : csr_vcycle<double>(h, r); };
    const Vector b = c.f;
    Vector z;
    h.vcycle(b, z);
    const Vector z_ref = reference(b);
    EXPECT_LE((z - z_ref).norm(), (single ? 2e-5 : 1e-12) * z_ref.norm()) << precision;
    Vector x1, x2;
    const LinearStats s1 = pcg(c.K, b, x1, [&](const Vector& r, Vector& y) { h.vcycle(r, y); }, 1e-8, 500);
    const LinearStats s2 = pcg(c.K, b, x2, [&](const Vector& r, Vector& y) { y = reference(r); }, 1e-8, 500);
    EXPECT_EQ(s1.status, LinearStatus::converged) << precision;
    EXPECT_EQ(s1.iterations, s2.iterations) << precision;
    EXPECT_LE((x1 - x2).norm(), 1e-6 * x2.norm()) << precision;
  }
}
