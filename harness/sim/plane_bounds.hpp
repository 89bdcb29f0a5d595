// Contact inside the minimisation (docs/newton.md): the ground planes y ≥ h of a Problem are
// bounds on the free particles' y coordinates, and Newton on E becomes projected Newton for bound
// constraints (Bertsekas 1982). At x, with g = h²∇E:
//  - the active set: free particles on the plane (y ≤ h) whose g_y ≥ 0 (E falls going down: the
//    plane pushes, with the multiplier g_y/h² ≥ 0);
//  - the step holds the ε-active set (Bertsekas' projected Newton): the particles within ε_k of
//    the plane whose g_y ≥ 0, ε_k = ‖x − P(x − M⁻¹g)‖_∞ over the free particles (the projected
//    inertial step's length: 0 exactly at a solution) — their y is held (K's row and column
//    fixed, g_y zeroed), the others take the Newton step of the free coordinates. With ε = 0 a
//    particle just above the plane that E pushes down takes a step the projection then cuts: the
//    ε-active set holds it instead, and shrinks to the active set as the iterates converge;
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
  // Bertsekas' ε_k at x for the gradient g (0 without planes).
  double epsilon(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& g) const;
  // Particles within eps of the plane whose g_y ≥ 0 (sorted): eps = 0 the active set, epsilon()
  // the ε-active set.
  void active_set(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& g, std::vector<int>& active, double eps = 0) const;
  // g_y = 0 at the active particles: the free gradient.
  static void free_gradient(const std::vector<int>& active, Eigen::Matrix3Xd& g);

 private:
  const Eigen::VectorXd& w_;
  bool any_ = false;
  double height_ = 0;  // the highest plane: y ≥ every plane's height
};

}  // namespace xb
