// The block-descent methods as outer methods of the stepper (harness/sim/block_descent.hpp): their
// position error against the reference falls towards 0 (not to a fixed point of their own), the
// stop test on ‖∇E‖ and its records, AVBD on a near-rigid and a rigid chain, the ground, and the
// refusals of keys they do not read.
#include "harness/io/run_record.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"
#include "harness/sim/sim_test_support.hpp"
#include "test_support.hpp"
#include "core/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace xb;
using xb::test::scene_params;

namespace {

RunResult run(Params p, const std::string& method, bool reference = true) {
  RunOptions opt;
  opt.reference = reference;
  return run_simulation(build_problem(p), p, method, opt);
}

double last_error(const RunResult& r) { return r.log.position_error.back(); }

}  // namespace

TEST(BlockDescent, VbdFallsToTheReferenceAndStopsOnGradE) {
  xb::test::OneThread one;
  Params p = scene_params("cloth_hang");
  p.resolution = 8;
  p.rtol = 1e-9;
  p.atol = 0;
  p.max_iterations = 3000;
  const RunResult r = run(p, "vbd");
  ASSERT_EQ(r.status, "ok") << r.message;
  ASSERT_EQ(r.log.substep_status.size(), 1u);
  // ‖∇E‖ to 1e-9 of its start, or to its rounding floor (here 1.4e-7: the cloth's α̃ = 1.1e-3 against m = 1)
  const std::string& end = r.log.substep_status[0];
  EXPECT_TRUE(end == "converged" || end == "rounding_floor") << end;
  EXPECT_LT(r.log.relative_newton_residual.back(), 1e-6);
  EXPECT_LT(last_error(r), 1e-5);  // the truth of the step, not a fixed point of its own
  EXPECT_GT(r.log.position_error.front(), 1e-1);
  EXPECT_EQ(r.log.dual_residual.back(), 0);  // λ = −C/α̃: E's own multipliers
  EXPECT_EQ(r.form_used, "none");
  const RunRecord rec = make_simulation_record("0001", p, "vbd", r);
  EXPECT_EQ(std::get<std::string>(rec.attrs.at("convergence_measure")), "energy_gradient");
  EXPECT_GT(std::get<double>(rec.attrs.at("colors")), 1);
}

TEST(BlockDescent, FixedIterationFrameAndChebyshev) {
  xb::test::OneThread one;
  Params p = scene_params("cloth_hang");
  p.resolution = 8;
  p.rtol = 0;
  p.atol = 0;
  p.max_iterations = 40;
  const RunResult plain = run(p, "vbd");
  EXPECT_EQ(plain.status, "max_iterations");
  EXPECT_EQ(plain.outer_iterations, 40);
  p.block_descent.vbd.acceleration = "chebyshev";
  p.block_descent.vbd.rho = 0.9;
  const RunResult fast = run(p, "vbd");
  EXPECT_EQ(fast.outer_iterations, 40);
  EXPECT_LT(last_error(fast), last_error(plain));
}

TEST(BlockDescent, AvbdOnANearRigidChainReachesTheReference) {
  xb::test::OneThread one;
  Params p = scene_params("pendulum");
  p.frames = 2;
  p.rtol = 1e-10;
  p.atol = 0;
  p.max_iterations = 2000;
  const RunResult r = run(p, "avbd");
  ASSERT_EQ(r.status, "ok") << r.message;
  for (size_t k = 0; k < r.log.iteration.size(); ++k)
    if (k + 1 == r.log.iteration.size() || r.log.iteration[k + 1] == 0) {
      EXPECT_LT(r.log.position_error[k], 1e-3);
    }
}

TEST(BlockDescent, AvbdTakesRigidConstraintsAndTheGround) {
  xb::test::OneThread one;
  Params p = scene_params("pendulum");
  p.variant = "rigid";
  apply_variant_keys(p);
  p.frames = 2;
  p.max_iterations = 500;
  const RunResult rigid = run(p, "avbd", false);
  ASSERT_TRUE(rigid.status == "ok" || rigid.status == "max_iterations") << rigid.message;
  EXPECT_LT(rigid.log.dual_residual.back(), 1e-6);  // ‖C‖ of the rigid links
  EXPECT_THROW(run(p, "vbd", false), Error);  // E has no term for a rigid constraint

  Params ball = scene_params("ball_drop");
  ball.frames = 12;  // in contact from frame 9
  const RunResult r = run(ball, "avbd", false);
  ASSERT_TRUE(r.status == "ok" || r.status == "max_iterations") << r.message;  // the stiff ball in 50 sweeps
  EXPECT_GE(r.final_positions.row(1).minCoeff(), -1e-6);
  EXPECT_GT(r.stats.at("ground_contacts"), 0);
}

TEST(BlockDescent, RefusesKeysItDoesNotRead) {
  Params p = scene_params("cloth_hang");
  p.resolution = 4;
  Params newton = p;
  newton.step = "newton";
  EXPECT_THROW(run(newton, "vbd", false), Error);
  Params rho = p;
  rho.block_descent.vbd.rho = 0.5;
  EXPECT_THROW(run(rho, "xpbd-gs", false), Error);
  EXPECT_THROW(run(rho, "avbd", false), Error);
  Params beta = p;
  beta.block_descent.avbd.beta = 5;
  EXPECT_THROW(run(beta, "vbd", false), Error);
  Params init = p;
  init.block_descent.vbd.init = "previous";
  EXPECT_NO_THROW(run(init, "avbd", false));
}
