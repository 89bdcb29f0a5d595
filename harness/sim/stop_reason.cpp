#include "stop_reason.hpp"

#include "../../core/error.hpp"

#include <cmath>

namespace xb {

std::string stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::running: return "running";
    case StopReason::converged: return "converged";
    case StopReason::rounding_floor: return "rounding_floor";
    case StopReason::line_search_at_floor: return "line_search_at_floor";
    case StopReason::trust_region_at_floor: return "trust_region_at_floor";
    case StopReason::max_iterations: return "max_iterations";
    case StopReason::line_search_failed: return "line_search_failed";
    case StopReason::trust_region_failed: return "trust_region_failed";
    case StopReason::stagnated: return "stagnated";
    case StopReason::solver_failed: return "solver_failed";
    case StopReason::not_finite: return "not_finite";
    case StopReason::diverged: return "diverged";
    case StopReason::interrupted: return "interrupted";
  }
  return "unknown";
}

StopReason stop_reason_from_name(const std::string& name) {
  for (int i = 0; i <= static_cast<int>(StopReason::interrupted); ++i)
    if (stop_reason_name(static_cast<StopReason>(i)) == name) return static_cast<StopReason>(i);
  throw Error("unknown stop reason '" + name + "'");
}

StopReason StopCriterion::test(int it, double r, double r0, double floor, bool finite) const {
  if (!finite || !std::isfinite(r)) return StopReason::not_finite;
  if (diverged(r, r0)) return StopReason::diverged;
  if (converged(r, r0)) return StopReason::converged;
  if (r <= floor_factor * floor) return StopReason::rounding_floor;
  if (it >= max_iterations) return StopReason::max_iterations;
  return StopReason::running;
}

}  // namespace xb
