// The export of a hierarchy's levels (hierarchy_export.hpp) is complete: a V-cycle written here
// from the exported CSR matrices, step coefficients, inverse (block) diagonals and coarsest matrix
// alone equals Hierarchy::vcycle, on a dual (scalar chebyshev, jacobi with level 0's λ, coarse
// smoother) and a primal (block_chebyshev, smoothed P, dropped blocks) system; its levels are the
// hierarchy's (rows, non-zeros, values), and it follows a values-only refresh.
#include "core/error.hpp"
#include "solvers/amg/hierarchy_export.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;

namespace {

// x = D⁻¹ b with the exported diagonal or node blocks.
Vector apply_dinv(const SmootherExport& s, const Vector& b) {
  if (s.node_start.empty()) return s.inv_diag.cwiseProduct(b);
  Vector y(b.size());
  long off = 0;
  for (size_t I = 0; I + 1 < s.node_start.size(); ++I) {
    const int s0 = s.node_start[I], nb = s.node_start[I + 1] - s0;
    Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> M(s.block_inv.data() + off, nb, nb);
    y.segment(s0, nb) = M * b.segment(s0, nb);
    off += static_cast<long>(nb) * nb;
  }
  return y;
}

// `sweeps` sweeps of the exported steps from x (zero: x = 0 on entry).
void smooth(const SmootherExport& s, const SparseMatrix& A, const Vector& b, Vector& x, bool zero) {
  if (zero) x = Vector::Zero(b.size());
  Vector d = Vector::Zero(b.size());
  for (int sweep = 0; sweep < s.sweeps; ++sweep)
    for (const auto& c : s.steps) {
      d = c[0] * d + c[1] * apply_dinv(s, b - A * x);
      x += d;
    }
}

// Algorithm 2 on the export, in double.
Vector export_vcycle(const HierarchyExport& e, const Vector& b) {
  const int nl = static_cast<int>(e.levels.size());
  std::vector<Vector> rhs(nl), sol(nl);
  rhs[0] = b;
  for (int l = 0; l + 1 < nl; ++l) {
    const LevelExport& L = e.levels[l];
    smooth(L.smoother, L.A, rhs[l], sol[l], true);
    rhs[l + 1] = L.R * (rhs[l] - L.A * sol[l]);
  }
  const LevelExport& C = e.levels[nl - 1];
  if (e.coarse_solver == "smoother")
    smooth(C.smoother, C.A, rhs[nl - 1], sol[nl - 1], true);
  else
    sol[nl - 1] = Eigen::MatrixXd(C.A).llt().solve(rhs[nl - 1]);
  for (int l = nl - 2; l >= 0; --l) {
    sol[l] += e.levels[l].P * sol[l + 1];
    smooth(e.levels[l].smoother, e.levels[l].A, rhs[l], sol[l], false);
  }
  return sol[0];
}

// The export's levels are the hierarchy's, and its V-cycle is the hierarchy's.
void check_export(Hierarchy& h, const std::string& what) {
  const HierarchyExport e = export_hierarchy(h);
  ASSERT_EQ(static_cast<int>(e.levels.size()), h.num_levels()) << what;
  ASSERT_GE(h.num_levels(), 3) << what << ": too few levels to test the recursion";
  for (int l = 0; l < h.num_levels(); ++l) {
    const LevelExport& L = e.levels[l];
    EXPECT_EQ(L.A.rows(), h.level_rows()[l]) << what << " level " << l;
    EXPECT_EQ(L.A.nonZeros(), h.level_nnz()[l]) << what << " level " << l;
    EXPECT_EQ((L.A - h.matrix(l)).norm(), 0.0) << what << " level " << l;
    if (l + 1 < h.num_levels()) {
      EXPECT_EQ(L.P.rows(), L.A.rows());
      EXPECT_EQ(L.P.cols(), h.level_rows()[l + 1]);
      EXPECT_EQ((Eigen::MatrixXd(L.R) - Eigen::MatrixXd(L.P).transpose()).norm(), 0.0) << what << ": R is not Pᵀ";
      EXPECT_TRUE(L.smoother.polynomial) << what;
      EXPECT_EQ(L.smoother.lambda_max, h.level(l).smoother->lambda_max()) << what << " level " << l;
    }
  }
  const Vector b = xb::test::random_vector(h.matrix(0).rows(), 7);
  Vector x;
  h.vcycle(b, x);
  EXPECT_LE((export_vcycle(e, b) - x).norm(), 1e-10 * x.norm()) << what;
}

}  // namespace

TEST(AmgHierarchyExport, DualLevelsAndVcycleAreTheHierarchys) {
  const auto s = xb::test::scene_system("cloth_hang", 24, 1);
  AmgOptions o;
  o.max_coarse = 40;
  o.precision = "double";
  Hierarchy h;
  h.setup(s.ds->A(), o, {});
  check_export(h, "dual chebyshev");
  const HierarchyExport e = export_hierarchy(h);
  EXPECT_EQ(e.levels[0].smoother.kind, "chebyshev");
  EXPECT_EQ(e.levels[0].smoother.steps.size(), 3u);  // the default degree
  EXPECT_TRUE(e.levels.back().smoother.kind.empty());  // coarse_solver = direct
  o.smoother.kind = "jacobi";
  o.jacobi_omega = "level0";
  o.coarse_solver = "smoother";
  h.setup(s.ds->A(), o, {});
  check_export(h, "dual jacobi, level 0's lambda, coarse smoother");
  const HierarchyExport j = export_hierarchy(h);
  EXPECT_EQ(j.levels[1].smoother.lambda_max, j.levels[0].smoother.lambda_max);
  EXPECT_EQ(j.levels.back().smoother.kind, "jacobi");
  // A values-only refresh: the export follows (new Galerkin values, new diagonals and λ).
  SparseMatrix A2 = s.ds->A();
  const Vector scale = xb::test::random_vector(A2.rows(), 3).array().abs() + 1.0;
  A2 = scale.asDiagonal() * A2 * scale.asDiagonal();
  ASSERT_TRUE(h.refresh(A2));
  check_export(h, "dual after refresh");
  EXPECT_NE(export_hierarchy(h).levels[1].A.coeffs()[0], j.levels[1].A.coeffs()[0]);
}

TEST(AmgHierarchyExport, PrimalBlockLevelsAndVcycleAreTheHierarchys) {
  const auto& c = xb::test::small_bar();
  AmgOptions o;
  o.max_coarse = 30;
  o.precision = "double";
  Hierarchy h;
  h.setup(c.K, o, {3, &c.rigid});
  check_export(h, "primal block_chebyshev");
  const HierarchyExport e = export_hierarchy(h);
  EXPECT_EQ(e.block_size, 3);
  EXPECT_EQ(e.levels[0].smoother.kind, "block_chebyshev");
  EXPECT_FALSE(e.levels[0].smoother.node_start.empty());
  EXPECT_EQ(e.levels[0].smoother.block_inv.size(), 9 * c.K.rows() / 3);
  EXPECT_EQ(e.levels[0].smoother.steps.size(), 4u);  // the primal default degree
}

TEST(AmgHierarchyExport, SingleIsTheResolvedPrecisionAndAnEmptyHierarchyIsRefused) {
  const auto s = xb::test::scene_system("cloth_hang", 12, 0);
  Hierarchy h;
  EXPECT_THROW(export_hierarchy(h), Error);
  AmgOptions o;
  o.max_coarse = 20;
  h.setup(s.ds->A(), o, {});
  EXPECT_EQ(export_hierarchy(h).precision, "single");  // auto with chebyshev
  EXPECT_EQ(export_hierarchy(h).coarse_solver, "direct");
}
