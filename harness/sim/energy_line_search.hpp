// The line search of Newton on E (harness/sim/newton_loop.hpp), along x(t) = P(x + tΔx) for
// t = 1, 1/2, …, 1e-9 (P: the plane bounds' projection, the identity without colliders). The
// decrease is measured against the slope along the path, Δ(t) = ∇E·(x(t) − x) < 0:
//  - armijo: E(x(t)) ≤ E(x) + c·Δ(t), c = 1e-4 (sufficient decrease);
//  - robust_armijo (the default): the same, and where the computed E(x(t)) − E(x) is within the
//    rounding of the two E's (2·energy_rounding(x), harness/sim/newton.hpp) the change of E by the
//    trapezoid rule on the gradients,
//    ΔE ≈ ½(x(t) − x)·(∇E(x) + ∇E(x(t))) ≤ c·Δ(t): exact for a quadratic and free of E's
//    cancellation, so a stiff scene keeps descending below E's resolution, where plain Armijo
//    blocks (Longva et al. 2023's robust line search; polysolve's RobustArmijo, without its
//    extra error term, which rejects the full Newton step of a quadratic).
// The accepted trial's constraint state and gradient are handed back for the next iteration.
#pragma once

#include "plane_bounds.hpp"

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <Eigen/Dense>

#include <functional>
#include <string>

namespace xb {

enum class LineSearchKind { armijo, robust_armijo };
LineSearchKind parse_line_search(const std::string& name);  // throws xb::Error for an unknown name

constexpr double armijo_c = 1e-4;
constexpr double energy_search_min_step = 1e-9;  // below it the search has failed (30 halvings)

struct EnergySearch {
  double t = 0;             // the step taken (0: failed)
  int trials = 0;           // energy evaluations spent
  bool accepted = false;
  bool on_gradient = false; // accepted by the trapezoid test (E could not resolve the decrease)
  double energy = 0;        // E at the accepted trial (E(x) if failed)
};

// What the search reads at x: E(x), g = h²∇E(x) per particle (0 at pins), and E's rounding at x
// (energy_rounding; 0: the trapezoid test never engages).
struct LineSearchStart {
  const Eigen::Matrix3Xd& x;
  const Eigen::Matrix3Xd& dx;
  const Eigen::Matrix3Xd& g;
  double energy;
  double energy_rounding = 0;
};

// The trial's state, kept for the caller: x(t), its constraints and h²∇E(x(t)).
struct LineSearchTrial {
  Eigen::Matrix3Xd x, g;
  ConstraintState state;
  Eigen::VectorXd lambda;
};

// Evaluates the constraints at a trial point (default: evaluate_constraints with Newton's rest cut).
using ConstraintEvaluator = std::function<void(const Eigen::Matrix3Xd& x, ConstraintState& state)>;

class EnergyLineSearch {
 public:
  EnergyLineSearch(const Problem& prob, const DualSystem& ds, const Eigen::VectorXd& alpha_tilde, double h,
                   LineSearchKind kind, const PlaneBounds* bounds = nullptr, ConstraintEvaluator evaluate = {});
  // Searches from `start` (x feasible); on acceptance `trial` holds x(t), its state and gradient.
  EnergySearch search(const LineSearchStart& start, const Eigen::Matrix3Xd& x_pred, LineSearchTrial& trial) const;

 private:
  const Problem& prob_;
  const DualSystem& ds_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  LineSearchKind kind_;
  const PlaneBounds* bounds_;
  ConstraintEvaluator evaluate_;
};

}  // namespace xb
