// Why a Newton solve of one substep stopped: one enum that the stepper, the reference and the
// records read (after polysolve's Status, the design card's model). The names are the recorded
// per-substep statuses (results/README.md: newton_status, reference/status).
#pragma once

#include <string>

namespace xb {

enum class StopReason {
  running,             // not stopped yet
  converged,           // ‖∇E‖ ≤ rtol of its first value, or ≤ atol
  rounding_floor,      // ‖∇E‖ within its own rounding error (newton.hpp: gradient_rounding_floor): success
  max_iterations,      // the iteration limit, above both
  line_search_failed,  // no step passed the line search and ‖∇E‖ is above its rounding floor
  trust_region_failed, // the trust region's radius collapsed with every step rejected, above the floor
  solver_failed,       // the linear solve broke down on the most projected Hessian too
  not_finite,          // a non-finite position, energy or gradient
  diverged,            // ‖∇E‖ grew 1e8-fold over its first value
  interrupted,         // stopped by the caller (time budget, capture)
};

// "converged", "rounding_floor", ...
std::string stop_reason_name(StopReason r);
// converged or rounding_floor: the substep's solution is found to the precision that exists.
inline bool stop_reason_success(StopReason r) { return r == StopReason::converged || r == StopReason::rounding_floor; }

}  // namespace xb
