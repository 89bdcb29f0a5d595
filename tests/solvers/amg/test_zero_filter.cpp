// amg.drop_tolerance (zero_filter.hpp) and the merge of small aggregates (nodal.hpp): on the
// uniformly stretched tet-ARAP bar most of K's off-diagonal blocks are round-off; the hierarchy
// drops them, keeps A_F − K positive semi-definite whatever the values, aggregates along the
// couplings that are left, and is rebuilt once a dropped coupling becomes real.
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/zero_filter.hpp"
#include "core/error.hpp"
#include "test_amg_primal.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace xb;
using namespace xb::amg;
using xb::test::primal_case;
using xb::test::PrimalCase;
using xb::test::solver_params;

namespace {
using Dense = Eigen::MatrixXd;

const PrimalCase& stretched_bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "4"}, {"prestretch", "1.05"}}, 0, 0);
  return c;
}

BlockPattern pattern_of(const SparseMatrix& K) {
  const NodeLayout nodes = NodeLayout::uniform(static_cast<int>(K.rows()), 3);
  BlockPattern p;
  EXPECT_TRUE(p.build(K, nodes, nodes));
  return p;
}

double min_eigenvalue(const Dense& S) { return Eigen::SelfAdjointEigenSolver<Dense>(S).eigenvalues().minCoeff(); }

}  // namespace

// The stretched bar: most blocks go, the kept entries are K's own, and what was dropped is
// round-off (A_F − K tiny and positive semi-definite).
TEST(AmgZeroFilter, DropsTheStretchedBarsRoundOffBlocks) {
  const SparseMatrix& K = stretched_bar().K;
  ZeroBlockFilter f;
  ASSERT_TRUE(f.build(K, pattern_of(K), 1e-10));
  EXPECT_GT(f.dropped_blocks(), 0);
  const SparseMatrix& F = f.matrix();
  EXPECT_LT(F.nonZeros(), K.nonZeros() / 2) << F.nonZeros() << " of " << K.nonZeros();
  EXPECT_EQ(f.source_nonzeros(), K.nonZeros());
  for (int i = 0; i < F.outerSize(); ++i)
    for (SparseMatrix::InnerIterator it(F, i); it; ++it)
      if (it.row() != it.col()) ASSERT_EQ(it.value(), K.coeff(it.row(), it.col()));
  const Dense D = Dense(F) - Dense(K);
  EXPECT_LE(D.norm(), 1e-12 * Dense(K).norm());
  EXPECT_GE(min_eigenvalue(D), -1e-15 * Dense(K).norm());
  EXPECT_TRUE(f.refresh(K));  // the same values: still negligible, A_F as built
  EXPECT_LE((Dense(f.matrix()) - Dense(K)).norm(), 1e-12 * Dense(K).norm());
}

// Dropped blocks given real values (same pattern): refresh() says so, and the refreshed A_F still
// lies above the matrix (the lumps), so a V-cycle on it stays SPD.
TEST(AmgZeroFilter, RefreshLumpsBlocksThatCameAlive) {
  const SparseMatrix& K = stretched_bar().K;
  ZeroBlockFilter f;
  ASSERT_TRUE(f.build(K, pattern_of(K), 1e-10));
  SparseMatrix K2 = K;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Dense E = Dense::Zero(K.rows(), K.cols());
  for (int i = 0; i < K.outerSize(); ++i)
    for (SparseMatrix::InnerIterator it(K, i); it; ++it) {
      const auto r = it.row(), c = it.col();
      if (r < c && f.matrix().coeff(r, c) == 0.0 && r / 3 != c / 3)
        E(r, c) = E(c, r) = 0.05 * std::sqrt(K.coeff(r, r) * K.coeff(c, c)) * u(rng);
    }
  for (int i = 0; i < K2.outerSize(); ++i)
    for (SparseMatrix::InnerIterator it(K2, i); it; ++it) it.valueRef() += E(it.row(), it.col());
  ASSERT_GT(E.norm(), 0);
  EXPECT_FALSE(f.refresh(K2));
  const Dense D = Dense(f.matrix()) - Dense(K2);
  EXPECT_GE(min_eigenvalue(D), -1e-12 * Dense(K2).norm());
  EXPECT_GT(D.norm(), 0.5 * E.norm());  // the live blocks are lumped, not kept
  EXPECT_TRUE(f.refresh(K));
  EXPECT_LE((Dense(f.matrix()) - Dense(K)).norm(), 1e-12 * Dense(K).norm());
}

// Where no block is negligible (the cloth) nothing is copied and level 0 is the caller's K.
TEST(AmgZeroFilter, KeepsEveryBlockOfTheCloth) {
  const PrimalCase c = primal_case("cloth_hang", {{"resolution", "12"}}, 3, 0);
  ZeroBlockFilter f;
  EXPECT_FALSE(f.build(c.K, pattern_of(c.K), 1e-10));
  AmgOptions o;
  Hierarchy h;
  h.setup(c.K, o, {3, &c.rigid});
  EXPECT_EQ(&h.matrix(0), &c.K);
  Hierarchy hb;
  hb.setup(stretched_bar().K, o, {3, &stretched_bar().rigid});
  EXPECT_LT(hb.matrix(0).nonZeros(), stretched_bar().K.nonZeros());
}

// On a line (a chain of nodes) standard aggregation makes aggregates of 3; merged until at least 4
// nodes per aggregate on average, each aggregate still a connected run of the line.
TEST(AmgNodal, MergeSmallAggregatesOnALine) {
  const int n = 60;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 2.0);
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  SparseMatrix S(n, n);
  S.setFromTriplets(t.begin(), t.end());
  const Aggregates first = standard_aggregation(S);
  ASSERT_GT(first.num_aggregates * 4, n);  // the case the merge is for
  EXPECT_EQ(merge_small_aggregates(S, first, &standard_aggregation, 0).aggregate, first.aggregate);
  const Aggregates m = merge_small_aggregates(S, first, &standard_aggregation, 4);
  EXPECT_GE(n, 4 * m.num_aggregates);
  EXPECT_GT(m.num_aggregates, 1);
  ASSERT_EQ(static_cast<int>(m.roots.size()), m.num_aggregates);
  for (int a = 0; a < m.num_aggregates; ++a) EXPECT_EQ(m.aggregate[m.roots[a]], a);
  std::vector<int> lo(m.num_aggregates, n), hi(m.num_aggregates, -1), count(m.num_aggregates, 0);
  for (int i = 0; i < n; ++i) {
    const int a = m.aggregate[i];
    ASSERT_GE(a, 0);
    lo[a] = std::min(lo[a], i);
    hi[a] = std::max(hi[a], i);
    ++count[a];
  }
  for (int a = 0; a < m.num_aggregates; ++a) EXPECT_EQ(hi[a] - lo[a] + 1, count[a]) << "aggregate " << a;
}

// The stretched bar's primal mgpbd iterations at resolution 4 and 8 (defaults) stay within 30% of
// each other and far below those with every block kept (measured 17 / 16 against 29 / 41), and
// level 1 is at least 4 times coarser than level 0.
TEST(AmgPrimal, StretchedBarIterationsHoldAsTheResolutionDoubles) {
  const PrimalCase r8 = primal_case("bar_hang", {{"resolution", "8"}, {"prestretch", "1.05"}}, 0, 0);
  int its[2][2];
  for (int keep = 0; keep < 2; ++keep) {
    Params p = solver_params(1e-8);
    if (keep) p.amg.drop_tolerance = 0;
    int k = 0;
    for (const PrimalCase* c : {&stretched_bar(), &r8}) {
      Vector x;
      const LinearStats st = xb::test::solve_k(*c, p, "mgpbd", x, c->dual_measure());
      ASSERT_EQ(st.status, LinearStatus::converged);
      its[keep][k++] = st.iterations;
    }
  }
  // The filtered level 0 couples particles along lines only; the merged aggregates still coarsen
  // by at least amg.min_coarsening nodes each (3.5 unmerged: operator complexity 5.8 on r8).
  Hierarchy h;
  h.setup(r8.K, AmgOptions{}, {3, &r8.rigid});
  ASSERT_GE(h.num_levels(), 2);
  EXPECT_GE(h.level(0).nodes.num_nodes(), 4 * h.level(1).nodes.num_nodes());
  const int lo = std::min(its[0][0], its[0][1]), hi = std::max(its[0][0], its[0][1]);
  EXPECT_LE(hi, 1.3 * lo) << its[0][0] << " / " << its[0][1];
  EXPECT_LE(hi, 25);
  EXPECT_GT(its[1][1], 1.5 * its[0][1]) << "every block kept: " << its[1][0] << " / " << its[1][1];
}

// mgpbd's lazy setup: a refresh onto values where a dropped block is real rebuilds the hierarchy;
// the same values refresh as usual.
TEST(AmgPrimal, ZeroBlocksThatComeAliveForceAFullSetup) {
  const PrimalCase& c = stretched_bar();
  auto s = make_linear_solver("mgpbd", solver_params(1e-8));
  SetupContext ctx;
  ctx.block_size = 3;
  ctx.near_kernel = &c.rigid;
  s->setup(c.K, SetupKind::Structure, ctx);
  EXPECT_EQ(s->last_setup_action(), "setup");
  s->setup(c.K, SetupKind::Values, ctx);
  EXPECT_EQ(s->last_setup_action(), "refresh");
  // K plus a positive semi-definite term on K's pattern, Σ w (e_r − e_c)(e_r − e_c)ᵀ over every
  // coupled pair of rows of different particles: every dropped block comes alive, K2 stays SPD.
  Dense G = Dense::Zero(c.K.rows(), c.K.cols());
  for (int i = 0; i < c.K.outerSize(); ++i)
    for (SparseMatrix::InnerIterator it(c.K, i); it; ++it) {
      const auto r = it.row(), col = it.col();
      if (r >= col || r / 3 == col / 3) continue;
      const double w = 1e-3 * std::sqrt(c.K.coeff(r, r) * c.K.coeff(col, col));
      G(r, col) -= w;
      G(col, r) -= w;
      G(r, r) += w;
      G(col, col) += w;
    }
  SparseMatrix K2 = c.K;
  for (int i = 0; i < K2.outerSize(); ++i)
    for (SparseMatrix::InnerIterator it(K2, i); it; ++it) it.valueRef() += G(it.row(), it.col());
  s->setup(K2, SetupKind::Values, ctx);
  EXPECT_EQ(s->last_setup_action(), "setup");
  Vector x;
  EXPECT_EQ(s->solve(c.f, x).status, LinearStatus::converged);
}
