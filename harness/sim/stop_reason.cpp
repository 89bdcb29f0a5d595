#include "stop_reason.hpp"

namespace xb {

std::string stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::running: return "running";
    case StopReason::converged: return "converged";
    case StopReason::rounding_floor: return "rounding_floor";
    case StopReason::max_iterations: return "max_iterations";
    case StopReason::line_search_failed: return "line_search_failed";
    case StopReason::trust_region_failed: return "trust_region_failed";
    case StopReason::solver_failed: return "solver_failed";
    case StopReason::not_finite: return "not_finite";
    case StopReason::diverged: return "diverged";
    case StopReason::interrupted: return "interrupted";
  }
  return "unknown";
}

}  // namespace xb
