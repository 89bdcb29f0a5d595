// amg.refresh (refresh_rule.hpp and mgpbd's use of it): the rule's choices from PCG counts, and
// what each scope does to mgpbd's hierarchy between two primal systems of one cloth (same pattern,
// new values): keep leaves the preconditioner exactly as it was, fine renews level 0's smoother
// and keeps A_1, full renews A_1; each still preconditions CG on the new matrix.
#include "core/error.hpp"
#include "harness/params.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/refresh_rule.hpp"
#include "solvers/krylov/pcg.hpp"
#include "test_amg_primal.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace xb;
using namespace xb::amg;
using xb::test::rel_diff;
using xb::test::two_cloth_states;
using xb::test::TwoStates;

TEST(AmgRefreshRule, IterationsPerDecade) {
  EXPECT_DOUBLE_EQ(RefreshRule::rate(4, 1e-2), 2.0);
  EXPECT_DOUBLE_EQ(RefreshRule::rate(3, 1e-1), 3.0);
  EXPECT_EQ(RefreshRule::rate(5, 1.0), std::numeric_limits<double>::infinity());  // no progress
  EXPECT_EQ(RefreshRule::rate(5, 2.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(RefreshRule::rate(5, std::nan("")), std::numeric_limits<double>::infinity());
}

TEST(AmgRefreshRule, LagsWhileTheRateStaysWithinTheGrowth) {
  RefreshRule full("full", 1.5);
  full.refreshed();
  full.solved(3, 1e-1, true);
  EXPECT_EQ(full.next(), RefreshScope::full);
  for (const char* mode : {"fine", "keep"}) {
    const RefreshScope lagged = std::string(mode) == "fine" ? RefreshScope::fine : RefreshScope::keep;
    RefreshRule r(mode, 1.5);
    EXPECT_EQ(r.next(), RefreshScope::full) << "no solve yet";
    r.refreshed();
    r.solved(4, 1e-2, true);  // the reference: 2 per decade
    EXPECT_EQ(r.next(), lagged);
    r.solved(0, 1.0, true);  // a zero right-hand side: no information
    EXPECT_EQ(r.next(), lagged);
    r.solved(6, 1e-2, true);  // 3 per decade = 1.5 × the reference: still lagged
    EXPECT_EQ(r.next(), lagged);
    r.solved(4, 1e-1, true);  // 4 per decade (a looser tolerance, more per decade): refresh
    EXPECT_EQ(r.next(), RefreshScope::full);
    r.refreshed();
    EXPECT_EQ(r.next(), RefreshScope::full) << "refreshed, no solve since";
    r.solved(4, 1e-1, true);  // the new reference: 4 per decade
    r.solved(12, 1e-2, true);  // 6 = 1.5 × 4
    EXPECT_EQ(r.next(), lagged);
    r.solved(2, 1e-1, false);  // a breakdown
    EXPECT_EQ(r.next(), RefreshScope::full);
  }
  EXPECT_THROW(RefreshRule("lazy", 1.5), Error);
  EXPECT_THROW(RefreshRule("fine", 0.9), Error);
}

// The hierarchy's refresh_fine keeps A_1 and renews level 0's smoother and float copy.
TEST(AmgRefreshRule, RefreshFineKeepsTheCoarseLevels) {
  const TwoStates& s = two_cloth_states();
  AmgOptions o;
  o.max_coarse = 50;
  o.drop_tolerance = 0;
  Hierarchy h;
  h.setup(s.a.K, o, {3, &s.a.rigid});
  ASSERT_GE(h.num_levels(), 3);
  const Eigen::MatrixXd old1(h.matrix(1));
  const double lambda_old = h.level(0).smoother->lambda_max();
  ASSERT_TRUE(h.refresh_fine(s.b.K));
  EXPECT_NE(h.level(0).smoother->lambda_max(), lambda_old);
  EXPECT_LE(rel_diff(Eigen::MatrixXd(h.level(0).single.A.cast<double>()), Eigen::MatrixXd(s.b.K)), 1e-6);
  EXPECT_EQ(rel_diff(Eigen::MatrixXd(h.matrix(1)), old1), 0.0);
  const Eigen::MatrixXd new1(galerkin_product(h.level(0).T.R, s.b.K, h.level(0).T.P));
  ASSERT_GT(rel_diff(old1, new1), 1e-6);
  ASSERT_TRUE(h.refresh(s.b.K));
  EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(1)), new1), 1e-12);
}

// mgpbd with each amg.refresh: setup on K1 and a solve (the reference), then a values-only setup
// on K2: the action it logs, whether the V-cycle changed, and a converged solve of K2.
TEST(AmgRefreshRule, MgpbdKeepsRefinesOrRefreshes) {
  const TwoStates& s = two_cloth_states();
  for (const char* mode : {"full", "fine", "keep"}) {
    Params p;
    p.amg.max_coarse = 50;
    p.amg.refresh = mode;
    p.amg.refresh_growth = 1e6;  // never forced back to full here
    p.linear.tol = 1e-8;
    auto solver = make_linear_solver("mgpbd", p);
    SparseMatrix K = s.a.K;  // one matrix object, its values changed in place, as the stepper does
    SetupContext ctx;
    ctx.block_size = 3;
    ctx.near_kernel = &s.a.rigid;
    solver->setup(K, SetupKind::Structure, ctx);
    Vector x1, x2;
    ASSERT_EQ(solver->solve(s.a.f, x1).status, LinearStatus::converged);
    K = s.b.K;
    ASSERT_EQ(K.nonZeros(), s.a.K.nonZeros());
    ctx.near_kernel = &s.b.rigid;
    solver->setup(K, SetupKind::Values, ctx);
    const std::string expected = std::string(mode) == "full" ? "refresh" : std::string(mode) == "fine" ? "refresh_fine" : "reuse";
    EXPECT_EQ(solver->last_setup_action(), expected);
    const LinearStats st = solver->solve(s.b.f, x2);
    EXPECT_EQ(st.status, LinearStatus::converged) << mode;
    Vector r = s.b.f - s.b.K * x2;
    EXPECT_LE(r.norm(), 1e-7 * s.b.f.norm()) << mode;
    EXPECT_EQ(solver->statistics().at("reuse_count"), std::string(mode) == "keep" ? 1 : 0);
  }
}

// keep: the preconditioner after the values-only setup is the one before it, bit for bit (the
// float V-cycle reads its own copies): mgpbd's solve of K2 equals PCG on K2 preconditioned by a
// hierarchy set up on K1. Under the double V-cycle (which reads the caller's K) keep refreshes
// level 0 instead (fine).
TEST(AmgRefreshRule, KeepLeavesTheFloatVcycleAsItWas) {
  const TwoStates& s = two_cloth_states();
  Params p;
  p.amg.max_coarse = 50;
  p.amg.refresh = "keep";
  p.amg.refresh_growth = 1e6;
  SetupContext ctx;
  ctx.block_size = 3;
  for (const char* precision : {"single", "double"}) {
    p.amg.precision = precision;
    auto solver = make_linear_solver("mgpbd", p);
    SparseMatrix K = s.a.K;
    ctx.near_kernel = &s.a.rigid;
    solver->setup(K, SetupKind::Structure, ctx);
    Vector x;
    ASSERT_EQ(solver->solve(s.a.f, x).status, LinearStatus::converged);
    K = s.b.K;
    ctx.near_kernel = &s.b.rigid;
    solver->setup(K, SetupKind::Values, ctx);
    if (std::string(precision) == "double") {
      EXPECT_EQ(solver->last_setup_action(), "refresh_fine");
      continue;
    }
    ASSERT_EQ(solver->last_setup_action(), "reuse");
    const LinearStats st = solver->solve(s.b.f, x);
    AmgOptions o = p.amg;
    o.near_kernel.seed = o.smoother.seed = static_cast<unsigned>(p.seed);
    Hierarchy h;
    h.setup(s.a.K, o, {3, &s.a.rigid});
    EXPECT_TRUE(h.owns_level0());
    Vector y;
    const LinearStats ref = pcg(s.b.K, s.b.f, y, [&](const Vector& r, Vector& z) { h.vcycle(r, z); }, p.linear.tol,
                                p.linear.max_iterations);
    EXPECT_EQ(st.iterations, ref.iterations);
    ASSERT_EQ(x.size(), y.size());
    for (long i = 0; i < x.size(); ++i) ASSERT_EQ(x[i], y[i]) << i;
  }
}
