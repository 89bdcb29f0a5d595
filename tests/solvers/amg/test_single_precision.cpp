// amg.precision = single: the V-cycle on float copies of the levels is the double one to float
// round-off (not bit-equal: the option is not ignored), follows a values-only refresh, and
// preconditions double CG to 1e-8 in both forms; the Gauss–Seidel kinds are refused. The float
// V-cycle works whatever the scale of b and leaves the caller's floating-point mode as it was.
#include "core/error.hpp"
#include "harness/params.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/kernels.hpp"
#include "solvers/linear_solver.hpp"

#include "amg_test_support.hpp"
#include "test_amg_primal.hpp"

#include <gtest/gtest.h>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

using namespace xb;
using namespace xb::amg;

namespace {

double rel(const Vector& a, const Vector& b) { return (a - b).norm() / b.norm(); }

// V-cycles of A b in double and single precision, and their relative difference.
double vcycle_difference(const SparseMatrix& A, const Vector& b, AmgOptions o, const MatrixInfo& info) {
  Hierarchy hd, hs;
  o.precision = "double";
  hd.setup(A, o, info);
  o.precision = "single";
  hs.setup(A, o, info);
  EXPECT_GE(hs.num_levels(), 2);
  Vector xd, xs;
  hd.vcycle(b, xd);
  hs.vcycle(b, xs);
  return rel(xs, xd);
}

}  // namespace

TEST(AmgSinglePrecision, DualVcycleIsTheDoubleOneToFloatRoundOff) {
  const auto s = xb::test::scene_system("cloth_hang", 24, 1);
  AmgOptions o;
  o.max_coarse = 50;
  for (const std::string sm : {"chebyshev", "jacobi"}) {
    o.smoother.kind = sm;
    const double d = vcycle_difference(s.ds->A(), s.b, o, {});
    EXPECT_GT(d, 1e-9) << sm << ": single gives the double result: the option is ignored";
    EXPECT_LT(d, 1e-4) << sm;
  }
}

TEST(AmgSinglePrecision, PrimalBlockVcycleIsTheDoubleOneToFloatRoundOff) {
  const auto c = xb::test::primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  AmgOptions o;
  o.max_coarse = 30;
  for (const std::string sm : {"block_chebyshev", "block_jacobi", "chebyshev"}) {
    o.smoother.kind = sm;
    const double d = vcycle_difference(c.K, c.f, o, {3, &c.rigid});
    EXPECT_GT(d, 1e-9) << sm;
    EXPECT_LT(d, 1e-4) << sm;
  }
}

TEST(AmgSinglePrecision, RefreshUpdatesTheFloatCopies) {
  const auto s = xb::test::scene_system("cloth_hang", 24, 1);
  AmgOptions o;
  o.max_coarse = 50;
  o.precision = "double";
  Hierarchy hd, hs;
  hd.setup(s.ds->A(), o);
  o.precision = "single";
  hs.setup(s.ds->A(), o);
  const SparseMatrix A2 = 2.0 * s.ds->A();  // same pattern, new values: V-cycle halves
  hd.refresh(A2);
  hs.refresh(A2);
  Vector xd, xs;
  hd.vcycle(s.b, xd);
  hs.vcycle(s.b, xs);
  EXPECT_LT(rel(xs, xd), 1e-4);
}

TEST(AmgSinglePrecision, PcgStillConvergesTo1em8InBothForms) {
  const auto s = xb::test::scene_system("cloth_hang", 24, 1);
  Params p;
  p.linear.tol = 1e-8;
  p.amg.max_coarse = 50;
  int its[2];
  for (int single = 0; single < 2; ++single) {
    p.amg.precision = single ? "single" : "double";
    auto m = make_linear_solver("mgpbd", p);
    m->setup(s.ds->A(), SetupKind::Structure, {});
    Vector x;
    const LinearStats st = m->solve(s.b, x);
    EXPECT_EQ(st.status, LinearStatus::converged) << p.amg.precision;
    Vector r;
    residual(s.ds->A(), x, s.b, r);
    EXPECT_LE(norm2(r) / norm2(s.b), 1.01e-8) << p.amg.precision;
    its[single] = st.iterations;
  }
  EXPECT_LE(its[1], its[0] + 2);

  const auto c = xb::test::primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  p.amg.precision = "single";
  p.amg.max_coarse = 30;
  Vector dx;
  const LinearStats st = xb::test::solve_k(c, p, "mgpbd", dx, c.dual_measure());
  EXPECT_EQ(st.status, LinearStatus::converged);
  Vector r;
  residual(c.A(), c.recover(dx), c.b, r);
  EXPECT_LE(norm2(r) / norm2(c.b), 1.01e-8);
}

// b far outside float's range (1e-40 is below its smallest normal number, 1e40 above its
// largest): the float V-cycle of c·b is c times that of b.
TEST(AmgSinglePrecision, TheScaleOfBDoesNotMatter) {
  const auto s = xb::test::scene_system("cloth_hang", 24, 1);
  AmgOptions o;
  o.max_coarse = 50;
  o.precision = "single";
  Hierarchy h;
  h.setup(s.ds->A(), o);
  Vector x1;
  h.vcycle(s.b, x1);
  for (const double c : {1e-40, 1e40}) {
    Vector xc;
    h.vcycle(c * s.b, xc);
    ASSERT_TRUE(xc.allFinite()) << c;
    EXPECT_LT(rel(xc / c, x1), 1e-6) << c;
  }
  Vector x0;
  h.vcycle(Vector::Zero(s.b.size()), x0);
  EXPECT_EQ(x0.norm(), 0.0);
}

#if defined(__SSE__)
// The float V-cycle flushes denormals on its threads (K's tiny entries made it 11× slower) and
// gives the caller's flush-to-zero / denormals-are-zero bits back, set or not.
TEST(AmgSinglePrecision, TheCallersFloatingPointModeIsRestored) {
  const auto c = xb::test::primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  AmgOptions o;
  o.max_coarse = 30;
  o.precision = "single";
  Hierarchy h;
  h.setup(c.K, o, {3, &c.rigid});
  const unsigned saved = _mm_getcsr(), ftz_daz = 0x8040;
  for (const unsigned bits : {0u, ftz_daz}) {
    _mm_setcsr((saved & ~ftz_daz) | bits);
    Vector x;
    h.vcycle(c.f, x);
    EXPECT_EQ(_mm_getcsr() & ftz_daz, bits);
    EXPECT_TRUE(x.allFinite());
  }
  _mm_setcsr(saved);
}
#endif

TEST(AmgSinglePrecision, GaussSeidelKindsAndUnknownNamesAreRefused) {
  AmgOptions o;
  o.precision = "single";
  for (const std::string sm : {"gs", "block_gs"}) {
    o.smoother.kind = sm;
    try {
      resolve_options(o, {});
      ADD_FAILURE() << sm << " accepted in single precision";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("amg.precision=single"), std::string::npos) << e.what();
    }
  }
  o.smoother.kind = "chebyshev";
  o.precision = "half";
  EXPECT_THROW(resolve_options(o, {}), Error);
  Params p;
  EXPECT_THROW(set_param(p, "amg.precision", "half", "test"), Error);
  set_param(p, "amg.precision", "single", "test");
  EXPECT_EQ(p.amg.precision, "single");
}

// The default, auto: float with the polynomial smoothers (the auto smoother is one), double with
// the Gauss–Seidel kinds; the solver's statistic says which ran.
TEST(AmgSinglePrecision, AutoIsSingleWithPolynomialSmoothersAndDoubleWithGaussSeidel) {
  AmgOptions o;
  EXPECT_EQ(o.precision, "auto");
  for (const std::string sm : {"auto", "jacobi", "chebyshev", "block_jacobi", "block_chebyshev"}) {
    o.smoother.kind = sm;
    EXPECT_EQ(resolve_options(o, {3, nullptr}).precision, "single") << sm;
  }
  for (const std::string sm : {"gs", "block_gs"}) {
    o.smoother.kind = sm;
    EXPECT_EQ(resolve_options(o, {3, nullptr}).precision, "double") << sm;
  }
  const auto s = xb::test::scene_system("cloth_hang", 16, 1);
  for (const std::string sm : {"chebyshev", "gs"}) {
    Params p;
    set_param(p, "amg.smoother", sm, "test");
    auto solver = make_linear_solver("mgpbd", p);
    solver->setup(s.ds->A(), SetupKind::Structure, SetupContext{});
    EXPECT_EQ(solver->statistics().at("single_precision"), sm == "chebyshev" ? 1.0 : 0.0) << sm;
  }
}
