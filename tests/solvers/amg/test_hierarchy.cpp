// The hierarchy's setup (hierarchy.hpp): a values-only refresh against a fresh Galerkin product,
// the options that resolve by block size.
#include "core/error.hpp"
#include "solvers/amg/galerkin.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/kernels.hpp"
#include "solvers/krylov/pcg.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgLazySetup, RefreshKeepsSizesAndMatchesAFreshGalerkinProduct) {
  SceneSystem s = scene_system("cloth_hang", 16, 0);
  const SparseMatrix A1 = s.ds->A();
  // New values, same pattern: the matrix one outer iteration later.
  SceneSystem s2 = scene_system("cloth_hang", 16, 1);
  const SparseMatrix& A2 = s2.ds->A();
  ASSERT_EQ(A1.nonZeros(), A2.nonZeros());
  ASSERT_GT((Eigen::Map<const Vector>(A1.valuePtr(), A1.nonZeros()) - Eigen::Map<const Vector>(A2.valuePtr(), A2.nonZeros())).norm(), 0);
  for (const std::string nk : {"ones", "gs"}) {
    AmgOptions o;
    o.max_coarse = 40;
    o.precision = "double";  // compared to 1e-12 (auto: a float V-cycle)
    o.near_kernel.kind = nk;
    o.near_kernel.vectors = 2;
    Hierarchy h;
    h.setup(A1, o);
    const std::vector<double> rows = h.level_rows(), nnz = h.level_nnz();
    ASSERT_GE(h.num_levels(), 3);
    h.refresh(A2);
    EXPECT_EQ(h.level_rows(), rows);
    EXPECT_EQ(h.level_nnz(), nnz);
    // A_1 and A_2 after the refresh are Pᵀ A P of the new values with the old P.
    const SparseMatrix A1c = galerkin_product(h.level(0).T.R, A2, h.level(0).T.P);
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(1)), Eigen::MatrixXd(A1c)), 1e-12) << nk;
    const SparseMatrix A2c = galerkin_product(h.level(1).T.R, A1c, h.level(1).T.P);
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(2)), Eigen::MatrixXd(A2c)), 1e-12) << nk;
    check_vcycle_spd(h, 2, "refreshed " + nk);
  }

  // The solver's policy: setup on Structure and at iteration 0 of every setup_interval-th frame
  // (once), refresh otherwise; the solve after a refresh is right.
  Params p;
  p.amg.setup_interval = 20;
  p.amg.max_coarse = 40;
  p.linear.tol = 1e-10;
  auto solver = make_linear_solver("mgpbd", p);
  struct Step {
    const SparseMatrix* A;
    SetupKind kind;
    SetupContext ctx;
    const char* action;
  };
  const std::vector<Step> steps = {
      {&A1, SetupKind::Structure, {0, 0, 0}, "setup"},   {&A2, SetupKind::Values, {0, 0, 1}, "refresh"},
      {&A1, SetupKind::Values, {1, 0, 0}, "refresh"},    {&A2, SetupKind::Values, {20, 0, 0}, "setup"},
      {&A1, SetupKind::Values, {20, 0, 0}, "refresh"},   {&A2, SetupKind::Values, {20, 1, 0}, "refresh"},
      {&A1, SetupKind::Values, {21, 0, 0}, "refresh"},   {&A2, SetupKind::Structure, {21, 0, 3}, "setup"}};
  const auto levels0 = solver->statistics();
  for (const Step& st : steps) {
    solver->setup(*st.A, st.kind, st.ctx);
    EXPECT_EQ(solver->last_setup_action(), st.action) << "frame " << st.ctx.frame << " it " << st.ctx.iteration;
    const Vector b = random_vector(st.A->rows(), 3);
    Vector x;
    const LinearStats ls = solver->solve(b, x);
    EXPECT_EQ(ls.status, LinearStatus::converged);
    Vector r;
    residual(*st.A, x, b, r);
    EXPECT_LE(r.norm(), 1e-10 * b.norm() * 1.01);
    EXPECT_NEAR(ls.final_relative_residual, r.norm() / b.norm(), 1e-14);
    EXPECT_GT(ls.iterations, 0);
    EXPECT_EQ(ls.residual_history.size(), static_cast<size_t>(ls.iterations + 1));
    EXPECT_EQ(ls.residual_time.size(), ls.residual_history.size());
  }
  const auto stats = solver->statistics();
  EXPECT_EQ(stats.at("setup_count"), 3);
  EXPECT_EQ(stats.at("refresh_count"), 5);
  EXPECT_GE(stats.at("levels"), 3);
  EXPECT_GT(stats.at("operator_complexity"), 1.0);
  EXPECT_GT(stats.at("grid_complexity"), 1.0);
  const auto arrays = solver->array_statistics();
  ASSERT_EQ(arrays.at("level_rows").size(), static_cast<size_t>(stats.at("levels")));
  EXPECT_EQ(arrays.at("level_rows")[0], A1.rows());
  double nnz_sum = 0;
  for (double v : arrays.at("level_nnz")) nnz_sum += v;
  EXPECT_NEAR(stats.at("operator_complexity"), nnz_sum / A1.nonZeros(), 1e-12);
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


// amg.coarse_refresh_interval = 2: the first refresh after a setup renews level 0's smoother (and
// its float copy) but keeps A_1 = Pᵀ A_old P; the second recomputes A_1 from the new values. At 1
// (the default) every refresh does. The V-cycle stays SPD either way.
TEST(AmgLazySetup, CoarseRefreshIntervalLagsTheCoarseLevels) {
  const TwoStates& s = two_cloth_states();
  const SparseMatrix &K1 = s.a.K, &K2 = s.b.K;
  ASSERT_EQ(K1.nonZeros(), K2.nonZeros());
  for (const int k : {1, 2}) {
    AmgOptions o;
    o.max_coarse = 50;
    o.coarse_refresh_interval = k;
    o.drop_tolerance = 0;  // level 0 is K itself
    Hierarchy h;
    h.setup(K1, o, {3, &s.a.rigid});
    ASSERT_GE(h.num_levels(), 3);
    const Eigen::MatrixXd old1(h.matrix(1));
    const Eigen::MatrixXd new1(galerkin_product(h.level(0).T.R, K2, h.level(0).T.P));
    ASSERT_GT(rel_diff(old1, new1), 1e-6);
    const double lambda_old = h.level(0).smoother->lambda_max();
    h.refresh(K2);
    EXPECT_NE(h.level(0).smoother->lambda_max(), lambda_old) << "level 0's smoother is refreshed every time";
    // level 0's float copy follows K2 whatever k
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.level(0).single.A.cast<double>()), Eigen::MatrixXd(K2)), 1e-6) << k;
    if (k == 1) {
      EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(1)), new1), 1e-12);
    } else {
      EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(1)), old1), 1e-15) << "a lagged refresh keeps A_1";
      EXPECT_LE(rel_diff(Eigen::MatrixXd(h.level(1).single.A.cast<double>()), old1), 1e-6);
    }
    // still a preconditioner for CG (the float V-cycle is symmetric to float round-off only)
    Vector x;
    const LinearStats st = pcg(K2, s.b.f, x, [&](const Vector& r, Vector& z) { h.vcycle(r, z); }, 1e-8, 300);
    EXPECT_EQ(st.status, LinearStatus::converged) << "after refresh 1, k = " << k;
    h.refresh(K2);
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.matrix(1)), new1), 1e-12) << "refresh 2 renews A_1 at k = " << k;
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.level(1).single.A.cast<double>()), new1), 1e-6) << k;
  }
}

// amg.prolongator_drop_tolerance: a sparser smoothed P (R still Pᵀ), so fewer non-zeros in A_1
// and in the operator complexity; a V-cycle that still preconditions CG. 0 keeps every block.
TEST(AmgLazySetup, ProlongatorDropToleranceThinsPAndTheCoarseLevels) {
  const xb::test::PrimalCase& c = two_cloth_states().a;
  std::vector<long> p_nnz;
  std::vector<double> oc;
  for (const double tol : {0.0, 0.3}) {
    AmgOptions o;
    o.max_coarse = 50;
    o.precision = "double";  // the SPD check below is to 1e-10
    o.prolongator_drop_tolerance = tol;
    Hierarchy h;
    h.setup(c.K, o, {3, &c.rigid});
    ASSERT_GE(h.num_levels(), 2);
    p_nnz.push_back(h.level(0).T.P.nonZeros());
    oc.push_back(h.operator_complexity());
    EXPECT_LE(rel_diff(Eigen::MatrixXd(h.level(0).T.R), Eigen::MatrixXd(h.level(0).T.P.transpose())), 0) << tol;
    EXPECT_FALSE(h.level(0).P_blocks.empty()) << "a filtered P keeps its node blocks";
    check_vcycle_spd(h, 2, "drop tolerance " + std::to_string(tol), SymmetryScale::energy);
  }
  EXPECT_LT(p_nnz[1], p_nnz[0]) << "the key is ignored";
  EXPECT_LT(oc[1], oc[0]);
}
