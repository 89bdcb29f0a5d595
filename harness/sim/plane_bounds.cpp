#include "plane_bounds.hpp"

#include <algorithm>

namespace xb {

PlaneBounds::PlaneBounds(const Problem& prob) : w_(prob.particles.w), any_(!prob.planes.empty()) {
  for (size_t i = 0; i < prob.planes.size(); ++i)
    height_ = i == 0 ? prob.planes[i].height : std::max(height_, prob.planes[i].height);
}

void PlaneBounds::project(Eigen::Matrix3Xd& x) const {
  if (!any_) return;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w_[p] > 0 && x(1, p) < height_) x(1, p) = height_;
}

double PlaneBounds::epsilon(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& g) const {
  double eps = 0;
  if (!any_) return eps;
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w_[p] > 0) {
      const double y = std::abs(x(1, p) - std::max(height_, x(1, p) - w_[p] * g(1, p)));
      eps = std::max({eps, y, w_[p] * std::abs(g(0, p)), w_[p] * std::abs(g(2, p))});
    }
  return eps;
}

void PlaneBounds::active_set(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& g, std::vector<int>& active,
                             double eps) const {
  active.clear();
  if (!any_) return;
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w_[p] > 0 && x(1, p) <= height_ + eps && g(1, p) >= 0) active.push_back(p);
}

void PlaneBounds::free_gradient(const std::vector<int>& active, Eigen::Matrix3Xd& g) {
  for (int p : active) g(1, p) = 0;
}

}  // namespace xb
