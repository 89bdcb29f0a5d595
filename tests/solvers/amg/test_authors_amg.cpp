// The authors' AMG variants (amg.coarse_solver = smoother, amg.jacobi_omega = level0,
// amg.near_kernel = gs_authors) against what each claims: the coarsest level gets exactly the
// smoother's sweeps from zero, every level uses level 0's λ_max, and the candidates are the
// authors' 30 sequential forward Gauss–Seidel sweeps handed to a smoothed prolongator.
#include "core/error.hpp"
#include "harness/params.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/amg/near_kernel.hpp"
#include "solvers/kernels.hpp"
#include "solvers/krylov/pcg.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

namespace {
AmgOptions jacobi_options() {
  AmgOptions o;
  o.smoother.kind = "jacobi";
  o.smoother.sweeps = 2;
  o.strength_threshold = 0.0;
  o.max_coarse = 50;
  o.precision = "double";  // the tests compare with double algebra (auto would run the V-cycle in float)
  return o;
}

int pcg_count(const SparseMatrix& A, Hierarchy& h, double tol) {
  const Vector b = random_vector(A.rows(), 5);
  Vector x;
  Preconditioner M = [&](const Vector& r, Vector& z) { h.vcycle(r, z); };
  const LinearStats st = pcg(A, b, x, M, tol, 500);
  EXPECT_EQ(st.status, LinearStatus::converged);
  return st.iterations;
}
}  // namespace

// One level: the V-cycle is the coarse solve. direct gives A⁻¹b; smoother gives two Jacobi sweeps
// from zero, x = ωD⁻¹b + ωD⁻¹(b − A ωD⁻¹b) with ω = 1/λ_max, written out here by hand.
TEST(AuthorsAmg, CoarseSolverSmootherIsTheSweepsFromZero) {
  const SparseMatrix A = poisson2d(12);
  const Vector b = random_vector(A.rows(), 3);
  AmgOptions o = jacobi_options();
  o.max_levels = 1;
  Hierarchy direct;
  direct.setup(A, o);
  Vector x;
  direct.vcycle(b, x);
  EXPECT_LE((A * x - b).norm(), 1e-10 * b.norm());
  o.coarse_solver = "smoother";
  Hierarchy smooth;
  smooth.setup(A, o);
  smooth.vcycle(b, x);
  const double omega = 1.0 / smooth.level(0).smoother->lambda_max();
  const Vector Dinv = A.diagonal().cwiseInverse();
  const Vector x1 = omega * Dinv.cwiseProduct(b);
  const Vector x2 = x1 + omega * Dinv.cwiseProduct(b - A * x1);
  EXPECT_LE((x - x2).norm(), 1e-12 * x2.norm());
  EXPECT_GT((A * x - b).norm(), 0.1 * b.norm());  // not a solve
  // Multilevel: still SPD (Gauss–Seidel gets its backward sweeps), and a weaker preconditioner.
  const SparseMatrix P = poisson2d(40);
  for (const std::string sm : {"jacobi", "gs"}) {
    AmgOptions m = jacobi_options();
    m.smoother.kind = sm;
    m.coarse_solver = "smoother";
    Hierarchy h;
    h.setup(P, m);
    ASSERT_GE(h.num_levels(), 2);
    check_vcycle_spd(h, 2, "coarse smoother " + sm);
  }
  AmgOptions m = jacobi_options();
  m.max_coarse = 400;
  Hierarchy hd, hs;
  hd.setup(P, m);
  m.coarse_solver = "smoother";
  hs.setup(P, m);
  EXPECT_GT(pcg_count(P, hs, 1e-8), pcg_count(P, hd, 1e-8));
}

// level0: every level's smoother uses level 0's λ_max (also after a refresh); per_level keeps
// each level's own, which differs on this matrix (so the test can tell the two apart).
TEST(AuthorsAmg, JacobiOmegaLevel0SharesLevelZerosLambda) {
  SceneSystem cloth = scene_system("cloth_hang", 24, 0);
  const SparseMatrix& A = cloth.ds->A();
  for (const std::string sm : {"jacobi", "chebyshev"}) {
    AmgOptions o = jacobi_options();
    o.smoother.kind = sm;
    o.coarse_solver = "smoother";
    Hierarchy own;
    own.setup(A, o);
    ASSERT_GE(own.num_levels(), 2);
    const double l0 = own.level(0).smoother->lambda_max();
    double max_gap = 0;
    for (int l = 1; l < own.num_levels(); ++l)
      max_gap = std::max(max_gap, std::abs(own.level(l).smoother->lambda_max() - l0) / l0);
    EXPECT_GT(max_gap, 0.05) << sm;
    o.jacobi_omega = "level0";
    Hierarchy shared;
    shared.setup(A, o);
    for (int l = 1; l < shared.num_levels(); ++l)
      EXPECT_EQ(shared.level(l).smoother->lambda_max(), shared.level(0).smoother->lambda_max()) << sm << " level " << l;
    const SparseMatrix A2 = 2.0 * A;
    shared.refresh(A2);
    for (int l = 1; l < shared.num_levels(); ++l)
      EXPECT_EQ(shared.level(l).smoother->lambda_max(), shared.level(0).smoother->lambda_max()) << sm << " refreshed";
    // The V-cycles differ: the coarse levels really smooth with the shared value.
    Vector x_own, x_shared;
    const Vector b = random_vector(A.rows(), 9);
    own.vcycle(b, x_own);
    shared.refresh(A);
    shared.vcycle(b, x_shared);
    EXPECT_GT((x_own - x_shared).norm(), 1e-6 * x_own.norm()) << sm;
  }
  AmgOptions g = jacobi_options();
  g.smoother.kind = "gs";
  g.jacobi_omega = "level0";
  EXPECT_THROW(resolve_options(g, {}), Error);
  g.jacobi_omega = "per_levels";
  EXPECT_THROW(resolve_options(g, {}), Error);
}

// gs_authors: 6 columns, each the direction of 30 sequential forward GS sweeps x ← −(D+L)⁻¹U x
// (a dense triangular solve here) from U[0,1)·max|A|; an auto prolongator becomes smoothed.
TEST(AuthorsAmg, GsAuthorsCandidatesAndSmoothedProlongator) {
  const SparseMatrix A = poisson2d(10);
  NearKernelOptions nk;
  nk.kind = "gs_authors";
  nk.seed = 4;
  nk.sweeps = 2;  // ignored: the recipe is fixed
  nk.vectors = 1;
  const Eigen::MatrixXd B = near_kernel_candidates(A, nk);
  ASSERT_EQ(B.cols(), kGsAuthorsVectors);
  const Eigen::MatrixXd Ad(A);
  const Eigen::MatrixXd DL = Ad.triangularView<Eigen::Lower>();
  const Eigen::MatrixXd U = Ad.triangularView<Eigen::StrictlyUpper>();
  const double max_abs = Ad.cwiseAbs().maxCoeff();
  for (int v = 0; v < kGsAuthorsVectors; ++v) {
    std::mt19937_64 rng(4ull * 1000003ull + static_cast<std::uint64_t>(v));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Eigen::VectorXd x(A.rows());
    for (long i = 0; i < x.size(); ++i) x[i] = u(rng) * max_abs;
    for (int s = 0; s < kGsAuthorsSweeps; ++s) x = -DL.triangularView<Eigen::Lower>().solve(U * x);
    x /= x.norm();
    EXPECT_LE((B.col(v) - x).norm(), 1e-10) << "vector " << v;
  }
  AmgOptions o = jacobi_options();
  o.near_kernel.kind = "gs_authors";
  EXPECT_EQ(resolve_options(o, {}).prolongator, "smoothed");
  o.prolongator = "tentative";
  EXPECT_EQ(resolve_options(o, {}).prolongator, "tentative");
  // In a hierarchy: P carries the 6 candidates (coarse rows = 6 per aggregate of ≥ 6 rows) and
  // is smoothed (rows with several entries), and the V-cycle preconditions CG.
  SceneSystem bar = scene_system("bar_hang", 3, 1);
  o.prolongator = "auto";
  Hierarchy h;
  h.setup(bar.ds->A(), o);
  ASSERT_GE(h.num_levels(), 2);
  EXPECT_GT(h.level(0).T.max_row_entries, kGsAuthorsVectors);
  EXPECT_GT(h.matrix(1).rows(), h.level(0).aggregates.num_aggregates);
  check_vcycle_spd(h, 2, "gs_authors");
  // This matrix is hard for 2 Jacobi sweeps whatever B is (ones: 238 iterations, gs_authors: 235).
  Hierarchy ones;
  ones.setup(bar.ds->A(), jacobi_options());
  EXPECT_LE(pcg_count(bar.ds->A(), h, 1e-8), pcg_count(bar.ds->A(), ones, 1e-8));
}

// The keys reach the options.
TEST(AuthorsAmg, ParamsKeys) {
  Params p;
  set_param(p, "amg.coarse_solver", "smoother", "test");
  set_param(p, "amg.jacobi_omega", "level0", "test");
  set_param(p, "amg.near_kernel", "gs_authors", "test");
  const AmgOptions o = p.amg;
  EXPECT_EQ(o.coarse_solver, "smoother");
  EXPECT_EQ(o.jacobi_omega, "level0");
  EXPECT_EQ(o.near_kernel.kind, "gs_authors");
  EXPECT_THROW(set_param(p, "amg.coarse_solver", "cholesky", "test"), Error);
  EXPECT_THROW(set_param(p, "amg.jacobi_omega", "level1", "test"), Error);
}
