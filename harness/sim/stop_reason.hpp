// Why an outer loop stopped in one substep, and the criterion that decides it (after polysolve's
// Status and Criteria, the design card's model): one enum the stepper, the reference and the
// records read, one stop test that sets it, one success predicate. The names are the recorded
// per-substep statuses (results/README.md: substep_status, reference/status); the predicate is
// recorded beside them (substep_success, reference/success), so that no reader re-derives it from
// the names.
#pragma once

#include <string>

namespace xb {

enum class StopReason {
  running,               // not stopped yet
  converged,             // the measure ≤ rtol of its first value, or ≤ atol
  rounding_floor,        // ‖∇E‖ within its own rounding error (newton.hpp: gradient_rounding_floor)
  line_search_at_floor,  // no step passed the line search, ‖∇E‖ within floor_factor_failed of its floor
  trust_region_at_floor, // the trust region collapsed (every step rejected), ‖∇E‖ within floor_factor_failed of its floor
  max_iterations,        // the iteration limit, above all of these
  line_search_failed,    // no step passed the line search, ‖∇E‖ farther above its floor
  trust_region_failed,   // the trust region collapsed, ‖∇E‖ farther above its floor
  stagnated,             // the measure stopped improving (the xpbd reference: no 1% gain in 5 iterations)
  solver_failed,         // the linear solve broke down (on the most projected Hessian too, under Newton)
  not_finite,            // a non-finite position, energy or measure
  diverged,              // the measure grew divergence_factor-fold over its first value
  interrupted,           // stopped by the caller (time budget, capture)
};

// "converged", "rounding_floor", ... (the recorded names).
std::string stop_reason_name(StopReason r);
// The reason of a recorded name; throws xb::Error for a name that is none.
StopReason stop_reason_from_name(const std::string& name);

// The one success predicate: the substep's solution is found to the precision that exists
// (converged, or ‖∇E‖ at its rounding floor). A line search that failed near the floor is not one.
inline bool stop_reason_success(StopReason r) { return r == StopReason::converged || r == StopReason::rounding_floor; }

// The stop criterion of an outer loop on its measure r (‖∇E‖ under Newton, the dual residual under
// XPBD), r0 its value at iteration 0.
struct StopCriterion {
  double rtol = 1e-8, atol = 0;
  int max_iterations = 100;
  static constexpr double divergence_factor = 1e8;    // r over this multiple of r0 (and over atol): diverged
  static constexpr double floor_factor = 1;           // r at or below this multiple of its rounding floor: rounding_floor
  static constexpr double floor_factor_failed = 1e2;  // a failed search below this multiple: *_at_floor

  bool diverged(double r, double r0) const { return r > divergence_factor * r0 && r > atol; }
  bool converged(double r, double r0) const { return r <= rtol * r0 || r <= atol; }
  // The reason to stop at iteration `it` (running: go on); floor: the measure's rounding floor (0: none).
  StopReason test(int it, double r, double r0, double floor, bool finite = true) const;
  // After a failed line search at measure r: line_search_at_floor or line_search_failed.
  static StopReason failed_search(double r, double floor) {
    return r <= floor_factor_failed * floor ? StopReason::line_search_at_floor : StopReason::line_search_failed;
  }
  // After the trust region collapsed at measure r, by the same floor: trust_region_at_floor or
  // trust_region_failed.
  static StopReason failed_region(double r, double floor) {
    return r <= floor_factor_failed * floor ? StopReason::trust_region_at_floor : StopReason::trust_region_failed;
  }
};

}  // namespace xb
