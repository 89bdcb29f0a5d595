#include "stability.hpp"

#include <cmath>
#include <sstream>

namespace xb {

StabilityBounds stability_bounds(const Problem& prob, const Params& p) {
  const Eigen::Matrix3Xd& x = prob.particles.x;
  Eigen::Vector3d lo = x.rowwise().minCoeff(), hi = x.rowwise().maxCoeff();
  // The rest shape may be larger than the start (squash starts collapsed): take the tets' rest
  // volumes' cube roots as a lower bound on the scene's size too.
  double L = (hi - lo).norm();
  double rest_volume = 0;
  for (double v : prob.tets.rest_volume) rest_volume += v;
  L = std::max(L, std::cbrt(rest_volume));
  for (double l : prob.distance.rest_length) L = std::max(L, l);
  if (!(L > 0)) L = 1;
  const double h = p.dt / p.substeps, T = p.dt * p.frames, g = prob.gravity.norm();
  const double v0 = prob.particles.v.cols() ? prob.particles.v.colwise().norm().maxCoeff() : 0;
  StabilityBounds b;
  b.max_speed = 10 * (L / h + g * T + v0);
  b.max_extent = 100 * L + g * T * T + v0 * T;
  return b;
}

int count_inverted_tets(const Problem& prob, const Eigen::Matrix3Xd& x) {
  const auto& T = prob.tets;
  int n = 0;
#pragma omp parallel for reduction(+ : n) schedule(static)
  for (int t = 0; t < static_cast<int>(T.size()); ++t) {
    const auto& e = T.idx[t];
    Eigen::Matrix3d Ds;
    for (int c = 0; c < 3; ++c) Ds.col(c) = x.col(e[c + 1]) - x.col(e[0]);
    if (!(Ds.determinant() > 0)) ++n;
  }
  return n;
}

StabilityMonitor::StabilityMonitor(const Problem& prob, const Params& p)
    : prob_(prob), bounds_(stability_bounds(prob, p)), has_tets_(prob.tets.size() > 0) {}

bool StabilityMonitor::check(const Particles& P, int frame, int substep, std::string& status, std::string& message) {
  const std::string at = " at frame " + std::to_string(frame) + ", substep " + std::to_string(substep);
  if (has_tets_) inverted_.push_back(count_inverted_tets(prob_, P.x));
  if (!P.x.allFinite() || !P.v.allFinite()) {
    status = "nan";
    message = "non-finite position or velocity" + at;
    return false;
  }
  const double speed = P.v.cols() ? P.v.colwise().norm().maxCoeff() : 0;
  const double extent = P.x.cols() ? (P.x.rowwise().maxCoeff() - P.x.rowwise().minCoeff()).norm() : 0;
  std::ostringstream os;
  os.precision(3);
  if (speed > bounds_.max_speed) {
    os << "runaway: speed " << speed << " m/s exceeds the scene's bound " << bounds_.max_speed << " m/s" << at;
    status = "diverged";
    message = os.str();
    return false;
  }
  if (extent > bounds_.max_extent) {
    os << "runaway: bounding-box diagonal " << extent << " m exceeds the scene's bound " << bounds_.max_extent << " m" << at;
    status = "diverged";
    message = os.str();
    return false;
  }
  return true;
}

}  // namespace xb
