// The block smoothers on node blocks (block_gs.hpp, block_chebyshev.hpp): a block Gauss–Seidel
// sweep against a dense node-by-node computation and on a block-diagonal system, the symmetry of
// the V-cycle with several sweeps, mgpbd with each block smoother against a direct solve, and the
// primal defaults' iteration advantage on the prestretched bar.
#include "solvers/amg/relaxation/block_gs.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/kernels.hpp"
#include "core/error.hpp"
#include "../test_amg_primal.hpp"

#include <Eigen/SparseCholesky>
#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <random>

using namespace xb;
using namespace xb::amg;
using xb::test::primal_case;
using xb::test::PrimalCase;

namespace {
using Dense = Eigen::MatrixXd;

const PrimalCase& bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}, {"prestretch", "1.05"}}, 1, 0);
  return c;
}

// One sweep node by node in the colouring's order, dense: x_I = D_I⁻¹(b_I − Σ_{J≠I} A_IJ x_J).
Vector dense_block_gs(const Dense& A, const NodeLayout& nodes, const Coloring& col, const Vector& b, Vector x,
                      bool forward) {
  std::vector<int> seq(col.order);
  if (!forward) {  // colours reversed; inside a colour the order does not matter
    seq.clear();
    for (int c = col.num_colors - 1; c >= 0; --c)
      for (int t = col.color_start[c]; t < col.color_start[c + 1]; ++t) seq.push_back(col.order[t]);
  }
  for (int I : seq) {
    const int s = nodes.node_start[I], bs = nodes.node_start[I + 1] - s;
    const Vector rI = b.segment(s, bs) - A.middleRows(s, bs) * x + A.block(s, s, bs, bs) * x.segment(s, bs);
    x.segment(s, bs) = A.block(s, s, bs, bs).llt().solve(rI);
  }
  return x;
}
}  // namespace

// On K (3×3 nodes) and on the first coarse level (nodes of varying size: an aggregate's kept QR
// columns), a forward and a backward sweep equal the dense node-by-node Gauss–Seidel.
TEST(AmgBlockGs, SweepEqualsDenseNodeByNodeGaussSeidel) {
  AmgOptions o;
  o.max_coarse = 30;
  Hierarchy h;
  h.setup(bar().K, o, {3, &bar().rigid});
  ASSERT_GE(h.num_levels(), 2);
  for (int l = 0; l < 2; ++l) {
    const SparseMatrix& A = h.matrix(l);
    const NodeLayout& nodes = h.level(l).nodes;
    ASSERT_FALSE(nodes.scalar());
    BlockDiagonal D;
    D.build(A, nodes);
    const Coloring col = node_coloring(A, nodes);
    EXPECT_GT(col.num_colors, 1);
    const Vector b = xb::test::random_vector(A.rows(), 3 + l), x0 = xb::test::random_vector(A.rows(), 7 + l);
    for (const bool forward : {true, false}) {
      Vector x = x0;
      block_gs_sweep(A, D, col, b, x, forward);
      const Vector ref = dense_block_gs(Dense(A), nodes, col, b, x0, forward);
      EXPECT_LE((x - ref).norm(), 1e-12 * ref.norm()) << "level " << l << (forward ? " forward" : " backward");
    }
  }
}

// A block-diagonal SPD system (nodes of sizes 3, 1, 6, 2, …) is solved exactly by one sweep from
// any start: no node sees a coupling, so each is solved by its own block's inverse.
TEST(AmgBlockGs, OneSweepSolvesABlockDiagonalSystem) {
  NodeLayout nodes;
  nodes.node_start = {0};
  for (int sz : {3, 1, 6, 2, 3, 5, 3}) nodes.node_start.push_back(nodes.node_start.back() + sz);
  const int n = nodes.node_start.back();
  Dense Ad = Dense::Zero(n, n);
  for (int I = 0; I < nodes.num_nodes(); ++I) {
    const int s = nodes.node_start[I], bs = nodes.node_start[I + 1] - s;
    const Dense G = Eigen::Map<const Dense>(xb::test::random_vector(bs * bs, 40 + I).data(), bs, bs);
    Ad.block(s, s, bs, bs) = G * G.transpose() + 0.5 * Dense::Identity(bs, bs);
  }
  const SparseMatrix A = Ad.sparseView();
  SmootherOptions so;
  so.kind = "block_gs";
  auto sm = make_smoother(so, A, nodes);
  EXPECT_EQ(sm->name(), "block_gs");
  const Vector b = xb::test::random_vector(n, 5);
  const Vector exact = Ad.llt().solve(b);
  Vector x = xb::test::random_vector(n, 6);
  sm->postsmooth(A, b, x);  // one backward sweep from a non-zero start
  EXPECT_LE((x - exact).norm(), 1e-12 * exact.norm());
  sm->presmooth(A, b, x, true);  // one forward sweep from zero
  EXPECT_LE((x - exact).norm(), 1e-12 * exact.norm());
}

// Several sweeps (forward^s before, backward^s after) keep the V-cycle symmetric and positive
// definite, for the block Gauss–Seidel and the block polynomial smoothers.
TEST(AmgBlockGs, VcycleWithSeveralSweepsIsSymmetricPositiveDefinite) {
  for (const std::string sm : {"block_gs", "block_chebyshev", "block_jacobi"})
    for (const int sweeps : {2, 3}) {
      AmgOptions o;
      o.smoother.kind = sm;
      o.smoother.sweeps = sweeps;
      o.max_coarse = 30;
      o.precision = "double";  // symmetric to round-off: 1e-10 is below float's (auto: single)
      Hierarchy h;
      h.setup(bar().K, o, {3, &bar().rigid});
      ASSERT_GE(h.num_levels(), 3);
      xb::test::check_vcycle_spd(h, 3, sm + " x" + std::to_string(sweeps), xb::test::SymmetryScale::energy);
    }
}

namespace {
}  // namespace

// mgpbd with each block smoother (auto sweeps: 2 on K) reaches 1e-8 on K (recomputed) and, solved
// further, equals Eigen's LDLᵀ solution, on the prestretched bar and on the cloth.
TEST(AmgBlockGs, MgpbdWithBlockSmoothersEqualsADirectSolve) {
  const PrimalCase cloth = primal_case("cloth_hang", {{"resolution", "16"}}, 3, 0);
  // Iteration caps (two sweeps each): measured bar 42 (block_gs), 28 (block_chebyshev, degree 4),
  // 90 (block_jacobi); cloth 8, 8, 12.
  for (const auto& [c, caps] : {std::pair<const PrimalCase*, std::array<int, 3>>{&bar(), {55, 36, 115}},
                                {&cloth, {14, 14, 20}}}) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Eigen::SparseMatrix<double>(c->K));
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    const Vector x_direct = ldlt.solve(c->f);
    int k = 0;
    for (const std::string sm : {"block_gs", "block_chebyshev", "block_jacobi"}) {
      Params p;
      p.linear.tol = 1e-8;
      p.linear.max_iterations = 5000;
      p.amg.smoother.kind = sm;
      p.amg.smoother.sweeps = 2;
      Vector x, r;
      const LinearStats st = solve_k(*c, p, "mgpbd", x);
      const std::string what = sm + " on " + std::to_string(c->K.rows()) + " rows: " + std::to_string(st.iterations);
      std::printf("%s\n", what.c_str());
      ASSERT_EQ(st.status, LinearStatus::converged) << what;
      residual(c->K, x, c->f, r);
      EXPECT_LE(r.norm(), 1e-8 * c->f.norm()) << what;
      EXPECT_LE(st.iterations, caps[k++]) << what;
      p.linear.tol = 1e-13;
      solve_k(*c, p, "mgpbd", x);
      EXPECT_LE((x - x_direct).norm(), 1e-9 * x_direct.norm()) << what;
    }
  }
}

// The primal defaults (block Chebyshev of degree 4, 1 sweep) on the prestretched bar, stopping on the dual
// residual: at most a fifth of dual Jacobi-PCG's iterations (the target) and fewer than
// the previous default (scalar Chebyshev, 1 sweep). Measured at resolution 6, aspect 4:
// dual jacobi-pcg 333, block chebyshev degree 3 x2 35, degree 4 x1 41, chebyshev
// degree 3 x1 64; asserted with a margin (1/6, 4/5).
TEST(AmgBlockGs, PrimalDefaultsBeatJacobiPcgAndTheScalarSmootherOnTheStretchedBar) {
  const PrimalCase c = primal_case("bar_hang", {{"resolution", "6"}, {"aspect", "4"}, {"prestretch", "1.05"}}, 1, 0);
  Params p;
  p.linear.tol = 1e-8;
  p.linear.max_iterations = 20000;
  auto jac = make_linear_solver("jacobi-pcg", p);
  jac->setup(c.A(), SetupKind::Structure, {});
  Vector x;
  const LinearStats dual = jac->solve(c.b, x);
  const LinearStats mg = solve_k(c, p, "mgpbd", x, c.dual_measure());
  p.amg.smoother.kind = "chebyshev";
  p.amg.smoother.sweeps = 1;
  p.amg.smoother.degree = 3;
  const LinearStats old = solve_k(c, p, "mgpbd", x, c.dual_measure());
  std::printf("dual jacobi-pcg %d, mgpbd primal default %d, scalar chebyshev x1 %d\n", dual.iterations, mg.iterations,
              old.iterations);
  ASSERT_EQ(dual.status, LinearStatus::converged);
  ASSERT_EQ(mg.status, LinearStatus::converged);
  ASSERT_EQ(old.status, LinearStatus::converged);
  EXPECT_LE(6 * mg.iterations, dual.iterations);
  EXPECT_LE(mg.iterations * 5, old.iterations * 4);
}

// auto resolves per form: the dual (block size 1) keeps the scalar Chebyshev with one sweep.
TEST(AmgBlockGs, AutoSmootherPerForm) {
  AmgOptions o = Params().amg;
  Eigen::MatrixXd B(6, 6);
  EXPECT_EQ(resolve_options(o, {1, nullptr}).smoother.kind, "chebyshev");
  EXPECT_EQ(resolve_options(o, {1, nullptr}).smoother.sweeps, 1);
  EXPECT_EQ(resolve_options(o, {3, &B}).smoother.kind, kBlockSmoother);
  EXPECT_EQ(resolve_options(o, {3, &B}).smoother.sweeps, kBlockSmootherSweeps);
  EXPECT_EQ(resolve_options(o, {1, nullptr}).smoother.degree, 3);
  EXPECT_EQ(resolve_options(o, {3, &B}).smoother.degree, kBlockChebyshevDegree);
  o.smoother.kind = "block_sor";
  EXPECT_THROW(resolve_options(o, {}), Error);
}
