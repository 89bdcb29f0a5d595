// The one way a system is captured from a scene (used by `capture`, the perf metrics, the
// benchmarks and the tests): run a global method until the outer iteration asked for is about
// to be solved, and keep its dual system with the data of its primal form.
#pragma once

#include "simulation.hpp"

#include "../io/system_io.hpp"

#include "../params.hpp"

#include <functional>
#include <string>

namespace xb {

// Throws xb::Error naming the key where the run would solve a system other than XPBD's dual step
// (step = newton, xpbd.geometric_stiffness != none, xpbd.primal_residual != zero): capture writes
// only that one. capture_system checks it first.
void check_capturable(const Params& p);

// Runs `driver` (a global method; cholmod by default elsewhere, so that the system does not depend
// on the solver under test) on the scene of `p` until the system of (frame, substep, iteration)
// is assembled, and returns it; p.frames is raised to reach the frame. Throws xb::Error saying
// where the run stopped if it never gets there (time_budget: s, 0 = none, and on_iteration as in
// RunOptions).
CapturedSystem capture_system(Params p, const std::string& driver, int frame, int substep, int iteration,
                              double time_budget = 0,
                              std::function<void(const IterationProgress&)> on_iteration = {});

}  // namespace xb
