// The trust region of Newton on E (harness/sim/trust_region.hpp, newton_trust_region.cpp): the
// radius rule, a problem with a known minimiser where line-search Newton converges to a saddle and
// the trust region does not, its records in a run, and the keys refused where they do not apply.
#include "harness/sim/newton_loop.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/residual_energy.hpp"
#include "harness/sim/simulation.hpp"
#include "harness/sim/trust_region.hpp"
#include "problems/constraint_hessian.hpp"
#include "problems/scene.hpp"
#include "harness/sim/sim_test_support.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace xb;
using xb::test::newton_params;

TEST(TrustRegion, RadiusRule) {
  const double r = 2;
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, 0.1, 1.0, false), 0.25);   // ρ < 1/4: a quarter of min(Δ, ‖p‖)
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, 0.1, 2.0, true), 0.5);
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, -3, 2.0, true), 0.5);      // an increase of E
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, NAN, 2.0, true), 0.5);     // a trial that is not finite
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, 0.5, 2.0, true), 2);       // between: kept
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, 0.9, 2.0, true), 4);       // ρ > 3/4 on the boundary: doubled
  EXPECT_DOUBLE_EQ(RadiusRule::next(r, 0.9, 1.0, false), 2);      // ... but not inside it
  EXPECT_FALSE(RadiusRule::accepted(0.005));
  EXPECT_TRUE(RadiusRule::accepted(0.02));
  EXPECT_FALSE(RadiusRule::accepted(NAN));
}

namespace {
// One free particle (unit mass) between pins at (∓1, 0, 0), both springs of rest length 2
// compressed (1/α̃ = 10), x̃ = (0.2, 0, 0). On the x axis the gradient has no transverse part, so
// any Newton step stays on it, ending at the axis' critical point s = 0.2/21, a saddle (transverse
// curvature 1 − 19 < 0). The minimisers are off the axis: a circle about it, (s*, r*) from the
// one-dimensional-in-r problem solved below.
constexpr double h = 0.1, k = 10, s_pred = 0.2;
Problem saddle_problem() {
  Problem prob;
  prob.name = "saddle";
  prob.particles.x.resize(3, 3);
  prob.particles.x << -1, 1, s_pred, 0, 0, 0, 0, 0, 0;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 3);
  prob.particles.w = Eigen::Vector3d(0, 0, 1);
  prob.distance.idx = {{0, 2}, {1, 2}};
  prob.distance.rest_length = {2.0, 2.0};
  prob.distance.compliance = {h * h / k, h * h / k};
  return prob;
}

// h²E in the plane (s, r): ½((s − s̃)² + r²) + k/2 Σ (l_j − 2)²; its minimiser by Newton on the
// analytic gradient and Hessian (no E of the harness involved).
Eigen::Vector2d plane_minimiser() {
  Eigen::Vector2d z(0.0, 1.0);
  for (int it = 0; it < 100; ++it) {
    Eigen::Vector2d g(z[0] - s_pred, z[1]);
    Eigen::Matrix2d H = Eigen::Matrix2d::Identity();
    for (double c : {-1.0, 1.0}) {
      const Eigen::Vector2d d(z[0] - c, z[1]);
      const double l = d.norm();
      const Eigen::Vector2d n = d / l;
      g += k * (l - 2) * n;
      H += k * (n * n.transpose() + (l - 2) / l * (Eigen::Matrix2d::Identity() - n * n.transpose()));
    }
    z -= H.ldlt().solve(g);
    if (g.norm() < 1e-14) break;
  }
  return z;
}

struct Outcome {
  NewtonOutcome o;
  Eigen::Vector3d x;
};
Outcome minimise(const std::string& solver, Params p) {
  const Problem prob = saddle_problem();
  p.dt = h;
  p.substeps = 1;
  p.rtol = 1e-11;
  p.atol = 0;
  p.max_iterations = 100;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  DualSystem ds(prob);
  GlobalStep step(prob, ds, solver, p, at);
  NewtonLoop loop(prob, ds, step, at, h, NewtonSettings::from(p));
  Eigen::Matrix3Xd x;
  Outcome out;
  out.o = loop.minimise(x, prob.particles.x, {});
  out.x = x.col(2);
  return out;
}
}  // namespace

TEST(TrustRegion, LineSearchNewtonEndsOnTheSaddle) {
  for (const std::string strategy : {"progressive", "on_demand", "clamp"}) {
    Params p = newton_params("mass_chain");
    p.hessian_projection = strategy;
    const Outcome r = minimise("cholmod", p);
    ASSERT_TRUE(stop_reason_success(r.o.reason)) << strategy << ": " << stop_reason_name(r.o.reason);
    EXPECT_NEAR(r.x[0], s_pred / (1 + 2 * k), 1e-9) << strategy;
    EXPECT_EQ(r.x[1], 0) << strategy;
    EXPECT_EQ(r.x[2], 0) << strategy;
    // ... a saddle: the transverse curvature of h²E there, 1 + k Σ C_j/l_j, is negative.
    const double s = r.x[0];
    EXPECT_LT(1 + k * ((s + 1 - 2) / (s + 1) + (1 - s - 2) / (1 - s)), -10) << strategy;
  }
}

TEST(TrustRegion, ReachesTheMinimiserFromTheSaddlesAxis) {
  const Eigen::Vector2d z = plane_minimiser();
  ASSERT_GT(z[1], 1);  // far off the axis
  for (const std::string sub : {"steihaug", "more_sorensen"}) {
    for (const std::string solver : {"cg", "cholmod"}) {
      if (sub == "more_sorensen" && solver != "cholmod") continue;
      Params p = newton_params("mass_chain");
      p.globalization = "trust_region";
      p.trust_region_subproblem = sub;
      const Outcome r = minimise(solver, p);
      ASSERT_TRUE(stop_reason_success(r.o.reason)) << sub << " " << solver << ": " << stop_reason_name(r.o.reason);
      EXPECT_NEAR(r.x[0], z[0], 1e-8) << sub << " " << solver;
      EXPECT_NEAR(std::hypot(r.x[1], r.x[2]), z[1], 1e-8) << sub << " " << solver;
    }
  }
}

// The squash's default ball under the trust region, with its records: every entry after the first
// has a radius and a ratio above the acceptance threshold, and the run matches its reference.
TEST(TrustRegion, RecordsPerIterationOnTheSquash) {
  for (const std::string sub : {"steihaug", "more_sorensen"}) {
    Params p = newton_params("squash");
    p.resolution = 6;
    p.globalization = "trust_region";
    p.trust_region_subproblem = sub;
    RunOptions opt;
    opt.reference = true;
    const RunResult r = run_simulation(build_problem(p), p, "cholmod", opt);
    ASSERT_EQ(r.status, "ok") << sub << ": " << r.message;
    const IterationLog& L = r.log;
    ASSERT_EQ(L.trust_region_radius.size(), L.iteration.size());
    ASSERT_EQ(L.trust_region_rejections.size(), L.iteration.size());
    for (size_t i = 0; i < L.iteration.size(); ++i) {
      if (L.iteration[i] == 0) continue;
      EXPECT_GT(L.trust_region_radius[i], 0) << sub << " " << i;
      EXPECT_GT(L.trust_region_ratio[i], RadiusRule::accept) << sub << " " << i;
    }
    EXPECT_EQ(L.inverted_elements.size(), L.iteration.size());
    EXPECT_LT(L.position_error.back(), 1e-6) << sub;
  }
}

TEST(TrustRegion, KeysAreRefusedWhereTheyDoNotApply) {
  const auto fails = [](Params p, const std::string& solver, const std::string& key) {
    try {
      run_simulation(build_problem(p), p, solver);
    } catch (const Error& e) {
      return std::string(e.what()).find(key) != std::string::npos;
    }
    return false;
  };
  Params xpbd = xb::test::scene_params("squash");
  xpbd.globalization = "trust_region";
  EXPECT_TRUE(fails(xpbd, "cholmod", "xpbd.globalization"));
  Params n = newton_params("squash");
  n.trust_region_subproblem = "more_sorensen";
  EXPECT_TRUE(fails(n, "cholmod", "xpbd.trust_region_subproblem"));  // without the trust region
  n.globalization = "trust_region";
  EXPECT_TRUE(fails(n, "mgpbd", "--solver cholmod"));
  Params ls = newton_params("squash");
  ls.globalization = "trust_region";
  ls.line_search = "armijo";
  EXPECT_TRUE(fails(ls, "cholmod", "xpbd.line_search"));
}
