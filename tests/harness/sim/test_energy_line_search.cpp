// The line search on E (harness/sim/energy_line_search.hpp) on a case where E is exactly quadratic
// along the search direction: one particle on a spring from a pin, moved along the spring's own
// direction (C = r − l₀ is linear in the radius r there), so E(r) = m(r − r̃)²/(2h²) + (r − l₀)²/(2α)
// and every decision can be predicted.
#include "harness/sim/energy_line_search.hpp"
#include "harness/sim/newton.hpp"
#include "harness/sim/residual_energy.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace xb;

namespace {
struct Spring {
  Problem prob;
  double h = 1e-2, m = 2, alpha = 1e-5, rest = 1, r_pred = 1.5;
  Eigen::Matrix3Xd x_pred;
  Eigen::VectorXd at;
  Spring() {
    prob.name = "spring";
    prob.particles.x = Eigen::Matrix3Xd::Zero(3, 2);
    prob.particles.v = Eigen::Matrix3Xd::Zero(3, 2);
    prob.particles.w = Eigen::Vector2d(0, 1 / m);
    prob.distance.idx = {{0, 1}};
    prob.distance.rest_length = {rest};
    prob.distance.compliance = {alpha};
    x_pred = at_radius(r_pred);
    at = scaled_compliance(prob, h);
  }
  // The particle at radius r along the unit direction (1, 2, 2)/3.
  Eigen::Matrix3Xd at_radius(double r) const {
    Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Zero(3, 2);
    x.col(1) = r * Eigen::Vector3d(1, 2, 2) / 3;
    return x;
  }
  // E's rounding at x (newton.hpp).
  double rounding(const Eigen::Matrix3Xd& x, double E) const {
    ConstraintState s;
    evaluate_constraints(prob, x, s);
    return energy_rounding(prob, s, x, x_pred, h, E);
  }
  // E and h²∇E at x.
  double energy(const Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& g) const {
    ConstraintState s;
    evaluate_constraints(prob, x, s);
    Eigen::VectorXd lambda;
    eliminate_multipliers(s, at, lambda);
    DualSystem ds(prob);
    primal_residual_vector(prob, ds, s, x, x_pred, lambda, g);
    return incremental_energy(prob, s, x, x_pred, h);
  }
  // The minimiser's radius: m(r − r̃)/h² + (r − l₀)/α = 0.
  double r_star() const { return (m / (h * h) * r_pred + rest / alpha) / (m / (h * h) + 1 / alpha); }
};
}  // namespace

// An overshoot of the Newton step by a = 1.99995 lowers E (E(x + aΔx) − E(x) = a(1 − a/2)·s < 0 for
// the slope s of the Newton step Δx) but by less than Armijo's c·a·s (a(1 − a/2) < c a): the search
// must shorten it. "E does not rise" in place of the sufficient decrease would take t = 1.
TEST(EnergyLineSearch, SufficientDecreaseRefusesAnOvershootThatLowersE) {
  const Spring c;
  DualSystem ds(c.prob);
  const Eigen::Matrix3Xd x = c.at_radius(1.2);
  Eigen::Matrix3Xd g;
  const double E = c.energy(x, g);
  const double a = 1.99995;
  const Eigen::Matrix3Xd dx = a * (c.at_radius(c.r_star()) - x);  // a × the exact Newton step
  Eigen::Matrix3Xd g1;
  const double E1 = c.energy(x + dx, g1);
  const double slope = particle_dot(c.prob, g, dx) / (c.h * c.h);
  ASSERT_LT(E1, E);                          // E falls at t = 1 ...
  ASSERT_GT(E1, E + armijo_c * slope);       // ... but not sufficiently
  for (const LineSearchKind kind : {LineSearchKind::armijo, LineSearchKind::robust_armijo}) {
    const EnergyLineSearch search(c.prob, ds, c.at, c.h, kind);
    LineSearchTrial trial;
    const EnergySearch s = search.search({x, dx, g, E, c.rounding(x, E)}, c.x_pred, trial);
    ASSERT_TRUE(s.accepted);
    EXPECT_EQ(s.t, 0.5);  // the quadratic's decrease at t = 1/2: a/2(1 − a/4)s, sufficient
    EXPECT_EQ(s.trials, 2);
    EXPECT_FALSE(s.on_gradient);
    EXPECT_LE(s.energy, E + armijo_c * s.t * slope);
  }
}

// Next to the minimiser a Newton step lowers E by ~1e-15, below E's own rounding (E ≈ 2e3, one ulp
// 4.5e-13; energy_rounding ≈ 9 ulps: the inertia's terms are computed from coordinates of ~1 and
// differ by ~0.4): the computed E cannot see it. With E(x) taken 8 ulps low (as a computed E may be), no
// trial can pass Armijo's test, so plain Armijo fails; the trapezoid rule on the gradients, exact
// for this quadratic, takes the full step onto the minimiser (robust_armijo).
TEST(EnergyLineSearch, RobustArmijoDescendsBelowTheRoundingOfE) {
  const Spring c;
  DualSystem ds(c.prob);
  const Eigen::Matrix3Xd x = c.at_radius(c.r_star() * (1 + 1e-10));
  Eigen::Matrix3Xd g;
  double E = c.energy(x, g);
  for (int k = 0; k < 8; ++k) E = std::nextafter(E, 0.0);
  const Eigen::Matrix3Xd dx = c.at_radius(c.r_star()) - x;
  const double slope = particle_dot(c.prob, g, dx) / (c.h * c.h);
  ASSERT_LT(-slope, 1e-15 * E);
  LineSearchTrial trial;
  const EnergySearch plain = EnergyLineSearch(c.prob, ds, c.at, c.h, LineSearchKind::armijo).search({x, dx, g, E}, c.x_pred, trial);
  EXPECT_FALSE(plain.accepted);
  const double rounding = c.rounding(x, E);
  ASSERT_GT(2 * rounding, 8 * (E - std::nextafter(E, 0.0)));
  const EnergySearch s =
      EnergyLineSearch(c.prob, ds, c.at, c.h, LineSearchKind::robust_armijo).search({x, dx, g, E, rounding}, c.x_pred, trial);
  ASSERT_TRUE(s.accepted);
  EXPECT_EQ(s.t, 1.0);
  EXPECT_TRUE(s.on_gradient);
  EXPECT_LT(std::sqrt(particle_dot(c.prob, trial.g, trial.g)), 1e-3 * std::sqrt(particle_dot(c.prob, g, g)));
}

// A direction that is not a descent direction is refused without a trial, by both searches.
TEST(EnergyLineSearch, RefusesAnAscentDirection) {
  const Spring c;
  DualSystem ds(c.prob);
  const Eigen::Matrix3Xd x = c.at_radius(1.2);
  Eigen::Matrix3Xd g;
  const double E = c.energy(x, g);
  for (const LineSearchKind kind : {LineSearchKind::armijo, LineSearchKind::robust_armijo}) {
    const EnergyLineSearch search(c.prob, ds, c.at, c.h, kind);
    LineSearchTrial trial;
    const EnergySearch s = search.search({x, g, g, E}, c.x_pred, trial);
    EXPECT_FALSE(s.accepted);
    EXPECT_EQ(s.trials, 0);
  }
  EXPECT_THROW(parse_line_search("wolfe"), std::exception);
}
