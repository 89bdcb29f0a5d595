// The certificate of a reference (harness/sim/certificate.hpp): its error bound against the true
// error of every iterate of a solve run to machine precision, the proof of a minimiser refused at a
// saddle, a reference stopped early not trusted, the position error's scale in free fall, and the
// records that carry it.
#include "harness/io/run_record.hpp"
#include "harness/sim/newton.hpp"
#include "harness/sim/reference.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"
#include "solvers/direct/spd_factor.hpp"
#include "harness/sim/sim_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace xb;
using xb::test::newton_params;

namespace {
struct Substep {
  Problem prob;
  Params p;
  Eigen::VectorXd at;
  Eigen::Matrix3Xd x_pred;
};

// The first substep of a stock scene under the newton profile.
Substep first_substep(const std::string& scene, const std::vector<std::pair<std::string, double>>& sets = {}) {
  Params p = newton_params(scene);
  for (const auto& [k, v] : sets) {
    if (k == "resolution") p.resolution = static_cast<int>(v);
    if (k == "stiffness") p.stiffness = v;
  }
  Substep s{build_problem(p), p, {}, {}};
  const double h = p.dt / p.substeps;
  s.at = scaled_compliance(s.prob, h);
  Particles& P = s.prob.particles;
  s.x_pred = P.x;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) s.x_pred.col(i) += h * (P.v.col(i) + h * s.prob.gravity);
  return s;
}
}  // namespace

// The reference after k = 1, 2, … iterations (the same path each time: the loop is deterministic)
// against the solve run to its rounding floor: wherever it is certified, its error estimate bounds
// its true error, ‖x_k − x*‖_M over the scale (up to x*'s own estimate); the bound is near the
// error (within 20×) wherever that error is well above x*'s, and the end itself is certified to
// 1e-10. On the stiff twisted bar and
// on the squash from its collapsed start (indefinite exact Hessians early: uncertified there).
TEST(Certificate, BoundsTheTrueErrorOfEveryIterate) {
  for (const std::string scene : {"twist_bar", "squash"}) {
    Substep s = scene == "twist_bar" ? first_substep(scene, {{"resolution", 2}, {"stiffness", 7e9}}) : first_substep(scene);
    ReferenceSolver full(s.prob, s.p, s.at, ReferenceSettings{0, 60});
    const ReferenceSolution star = full.solve(s.x_pred);
    ASSERT_TRUE(star.certified) << scene << ": " << star.certificate_note;
    EXPECT_LE(star.error_estimate, 1e-10) << scene;
    int certified = 0, tight = 0;
    for (int k = 1; k < star.iterations; ++k) {
      ReferenceSolver early(s.prob, s.p, s.at, ReferenceSettings{0, k});
      const ReferenceSolution r = early.solve(s.x_pred);
      const double truth = mass_norm_distance(s.prob, r.x, star.x) / r.error_scale;
      if (!r.certified) continue;
      ++certified;
      // x* carries its own error (its estimate): the bound must cover the truth up to it.
      EXPECT_GE(r.error_estimate + star.error_estimate, truth) << scene << " after " << k << " iterations (q = " << r.contraction << ")";
      if (truth > 1e3 * star.error_estimate) {
        EXPECT_LE(r.error_estimate, 20 * truth) << scene << " after " << k;
        ++tight;
      }
    }
    EXPECT_GE(certified, 2) << scene;
    EXPECT_GE(tight, 1) << scene;
  }
}

// Two compressed springs from a pin at x̃ (tests/harness/sim/test_newton_loop.cpp's saddle): the exact
// Hessian there is indefinite, so x̃ is not certified as a minimiser, whatever its gradient; CHOLMOD's
// LLᵀ refuses even a 2×2 indefinite matrix (its simplicial LDLᵀ would factorise it).
TEST(Certificate, AnIndefiniteHessianIsNotAMinimiser) {
  SparseMatrix A(2, 2);
  A.insert(0, 0) = 1;
  A.insert(0, 1) = 2;
  A.insert(1, 0) = 2;
  A.insert(1, 1) = 1;
  A.makeCompressed();
  SpdFactor f;
  std::string why;
  EXPECT_FALSE(f.factorise(A, why));
  EXPECT_NE(why.find("not positive definite"), std::string::npos) << why;
  A.coeffRef(1, 1) = 5;
  EXPECT_TRUE(f.factorise(A, why));
  Vector x;
  ASSERT_TRUE(f.solve(Vector::Ones(2), x));
  EXPECT_NEAR((A * x - Vector::Ones(2)).norm(), 0, 1e-14);

  const double h = 1e-2;
  Problem prob;
  prob.name = "springs";
  prob.particles.x.resize(3, 3);
  prob.particles.x << 0, 0.2, -0.1, 0, -0.1, -0.7, 0, 0.6, 0.9;
  prob.particles.v = Eigen::Matrix3Xd::Zero(3, 3);
  prob.particles.w = Eigen::Vector3d(0, 1, 1);
  prob.distance.idx = {{0, 1}, {1, 2}};
  prob.distance.rest_length = {1.0, 1.0};
  prob.distance.compliance = {0.5 * h * h, 0.5 * h * h};
  Params p = newton_params("mass_chain");
  p.dt = h;
  p.substeps = 1;
  const Eigen::VectorXd at = scaled_compliance(prob, h);
  ReferenceSolver ref(prob, p, at);
  const Certificate c = ref.certify(prob.particles.x, prob.particles.x);
  EXPECT_FALSE(c.positive_definite);
  EXPECT_EQ(c.error_bound, INFINITY);
  EXPECT_NE(c.note.find("not positive definite"), std::string::npos) << c.note;
  // Its minimiser is certified.
  const ReferenceSolution rs = ref.solve(prob.particles.x);
  EXPECT_TRUE(rs.certified) << rs.certificate_note;
}

// A reference stopped after one iteration on the squash is not trusted for a position error of 1e-4
// (its error estimate is above 1e-6, or it has no bound), and that estimate bounds its true error;
// the full reference (two iterations more) is trusted there.
TEST(Certificate, AReferenceStoppedEarlyIsNotTrustedFor1e4) {
  Substep s = first_substep("squash");
  const ReferenceSolution full = ReferenceSolver(s.prob, s.p, s.at).solve(s.x_pred);
  ASSERT_TRUE(stop_reason_success(full.status));
  EXPECT_TRUE(full.trusted(1e-4)) << full.certificate_note << " " << full.error_estimate;
  const ReferenceSolution early = ReferenceSolver(s.prob, s.p, s.at, ReferenceSettings{1e-10, 1}).solve(s.x_pred);
  EXPECT_EQ(early.status, StopReason::max_iterations);
  EXPECT_FALSE(early.trusted(1e-4));
  EXPECT_GT(early.certified_threshold(), 1e-4);
  EXPECT_GE(early.error_estimate, mass_norm_distance(s.prob, early.x, full.x) / early.error_scale);
}

// ball_drop's first substep is free fall: x̃ is its solution, ‖x_ref − x̃‖_M is rounding. The error
// scale is then √ε of the ball's size (mass-weighted), not that rounding: position errors stay
// small where they read ~1 before, and the reference is certified to 1e-6.
TEST(Certificate, FreeFallHasAScale) {
  Params p = newton_params("ball_drop");
  p.resolution = 4;
  p.frames = 1;
  RunOptions opt;
  opt.reference = true;
  const RunResult r = run_simulation(build_problem(p), p, "cholmod", opt);
  ASSERT_EQ(r.status, "ok") << r.message;
  ASSERT_EQ(r.log.reference_error_scale.size(), static_cast<size_t>(p.substeps));
  const Problem prob = build_problem(p);
  double mass = 0;
  for (int i = 0; i < prob.particles.size(); ++i) mass += prob.particles.w[i] > 0 ? 1 / prob.particles.w[i] : 0;
  const double body = std::sqrt(std::numeric_limits<double>::epsilon() * mass) * p.size;
  EXPECT_GT(r.log.reference_error_scale[0], 0.5 * body);
  EXPECT_LT(r.log.reference_error_scale[0], 3 * body);
  for (double e : r.log.position_error) EXPECT_LT(e, 1e-3);
  EXPECT_EQ(r.log.reference_certified[0], 1) << r.log.reference_certificate_note[0];
  EXPECT_LE(r.log.reference_error_estimate[0], 1e-6);
}

// A run with --reference records the certificate per substep, and the run's attributes its worst.
TEST(Certificate, EveryRecordCarriesIt) {
  Params p = newton_params("twist_bar");
  p.resolution = 2;
  p.stiffness = 7e9;
  RunOptions opt;
  opt.reference = true;
  const RunResult r = run_simulation(build_problem(p), p, "cholmod", opt);
  ASSERT_EQ(r.status, "ok") << r.message;
  const RunRecord rec = make_simulation_record("0001", p, "cholmod", r);
  for (const char* d : {"reference/error_estimate", "reference/certified", "reference/certified_threshold",
                        "reference/energy_gradient", "reference/gradient_floor", "reference/error_scale",
                        "reference/success", "reference/certificate_note", "substep_success"})
    EXPECT_TRUE(rec.datasets.count(d)) << d;
  EXPECT_EQ(std::get<long long>(rec.attrs.at("reference_substeps_uncertified")), 0);
  const double estimate = std::get<double>(rec.attrs.at("reference_error_estimate"));
  EXPECT_LE(estimate, 1e-6);
  EXPECT_DOUBLE_EQ(std::get<double>(rec.attrs.at("reference_certified_threshold")), 100 * estimate);
  EXPECT_GT(r.log.reference_gradient_floor[0], 0);
  EXPECT_GT(r.log.reference_energy_gradient[0], 0);
}
