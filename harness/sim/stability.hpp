// Stability checks after every substep. A failure becomes the run's status with a
// message; the stepper's own per-iteration checks cover residual blow-up (diverged), non-finite
// residuals (nan) and linear-solver breakdown (breakdown).
//   nan       a position or velocity is NaN or Inf
//   diverged  runaway growth: a speed above max_speed or a bounding box beyond max_extent
// For tet scenes the number of inverted tets (signed volume ≤ 0) is counted every substep and
// kept as a dataset; it does not end a run (squash starts with every tet flat).
#pragma once

#include "../params.hpp"
#include "../../problems/problem.hpp"

#include <string>
#include <vector>

namespace xb {

// Bounds scaled to the scene. L = the diagonal of the initial bounding box (of positions and of
// the rest shape), h = the substep, T = frames·dt, g = |gravity|, v0 = the largest initial speed:
//   max_speed  = 10·(L/h + g·T + v0)       anything faster crosses ten scene sizes per substep
//   max_extent = 100·L + g·T² + v0·T       the box's diagonal; free fall included
struct StabilityBounds {
  double max_speed = 0, max_extent = 0;
};
StabilityBounds stability_bounds(const Problem& prob, const Params& p);

class StabilityMonitor {
 public:
  StabilityMonitor(const Problem& prob, const Params& p);
  // Checks the particles after a substep. Returns false and sets status/message on a failure.
  bool check(const Particles& P, int frame, int substep, std::string& status, std::string& message);
  bool has_tets() const { return has_tets_; }
  // Per checked substep: inverted tets (tet scenes only; empty otherwise).
  const std::vector<double>& inverted_tets() const { return inverted_; }
  const StabilityBounds& bounds() const { return bounds_; }

 private:
  const Problem& prob_;
  StabilityBounds bounds_;
  bool has_tets_;
  std::vector<double> inverted_;
};

// Tets with signed volume ≤ 0 at x.
int count_inverted_tets(const Problem& prob, const Eigen::Matrix3Xd& x);

}  // namespace xb
