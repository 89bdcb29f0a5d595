// Contact inside the minimisation (docs/newton.md): the ground planes y ≥ h of a Problem are
// bounds on the free particles' y coordinates, and Newton on E becomes projected Newton for bound
// constraints (Bertsekas 1982). At x, with g = h²∇E:
//  - the active set: free particles on the plane (y ≤ h) whose g_y ≥ 0 (E falls going down: the
//    plane pushes, with the multiplier g_y/h² ≥ 0); their y is held in the step (K's row and
//    column fixed, g_y zeroed), the others take the Newton step of the free coordinates;
//  - the line search runs along the projected path P(x + tΔx) (energy_line_search.hpp);
//  - the stop test reads the free gradient: g with the active y zeroed. It is zero exactly where
//    x meets the contact's optimality conditions: no particle below the plane, no pulling contact
//    force (g_y ≥ 0 wherever the bound is active), ∇E = 0 in every other coordinate.
#pragma once

#include "../../problems/problem.hpp"

#include <Eigen/Dense>

#include <vector>

namespace xb {

class PlaneBounds {
 public:
  explicit PlaneBounds(const Problem& prob);
  bool empty() const { return !any_; }
  double height() const { return height_; }
  // y = max(y, h) for every free particle.
  void project(Eigen::Matrix3Xd& x) const;
  // Particles in the active set at x for the gradient g (sorted).
  void active_set(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& g, std::vector<int>& active) const;
  // g_y = 0 at the active particles: the free gradient.
  static void free_gradient(const std::vector<int>& active, Eigen::Matrix3Xd& g);

 private:
  const Eigen::VectorXd& w_;
  bool any_ = false;
  double height_ = 0;  // the highest plane: y ≥ every plane's height
};

}  // namespace xb
