// The one Newton loop on E (docs/newton.md): what `step = newton` runs for each substep and what
// `--reference` runs to make its solution. Its parts, each in a file named after it:
//   stop_reason.hpp          why it stopped (one enum), the stop criterion, the success predicate
//   hessian_projection.hpp   which element Hessians enter K projected, and what to try when a solve fails
//   energy_line_search.hpp   the line search on E (robust Armijo), along the projected path
//   plane_bounds.hpp         contact: the ground planes as bounds (projected Newton)
//   newton.hpp               h²∇E, the elimination of λ, the rounding floor of ‖∇E‖
//   trust_region.hpp         the trust region in place of the line search (newton_trust_region.cpp)
// One iteration: evaluate (reused from the line search's accepted trial) → stop test → direction
// (K Δx = −h²∇E with the strategy's projection; the descent safeguard: a try that breaks down, is
// not finite or is not a descent direction, ∇E·Δx ≥ 0, is solved again more projected) → line
// search. The caller watches through hooks (the stepper logs every iterate and checks its budget).
#pragma once

#include "energy_line_search.hpp"
#include "global_step.hpp"
#include "hessian_projection.hpp"
#include "plane_bounds.hpp"
#include "stop_reason.hpp"
#include "trust_region.hpp"

#include "../params.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace xb {

struct NewtonSettings {
  StopCriterion stop;  // on ‖∇E‖ (rtol: relative to its value at the start; atol in N)
  ProjectionStrategyKind projection = ProjectionStrategyKind::adaptive;  // xpbd.hessian_projection
  double exact_below = 1e-2;                                              // xpbd.exact_hessian_below
  LineSearchKind line_search = LineSearchKind::robust_armijo;
  Globalization globalization = Globalization::line_search;            // xpbd.globalization
  TrustRegionSubproblem subproblem = TrustRegionSubproblem::steihaug;  // xpbd.trust_region_subproblem
  int linear_max_iterations = 1000;  // Steihaug–Toint's CG (linear.max_iterations)
  // more_sorensen's direct solver (CHOLMOD with the run's settings, refactorised every setup).
  std::function<std::unique_ptr<LinearSolver>()> make_direct;
  static NewtonSettings from(const Params& p);
};

// The step that led to an iterate (all zero at iteration 0). What the records call linear_*,
// fill_time, step_time, step_length, line_search_trials, exact_hessian, projected_elements.
struct StepRecord {
  LinearStats linear;
  double time = 0;       // s in the whole step (fill, setup, solve, line search)
  double fill = 0;       // s filling K (inside the linear setup time), over the step's tries
  double hessians = 0;   // s filling the element Hessians (and, under XPBD, A), over the step's tries
  double length = 0;     // the line search's t (or ω)
  double tolerance = 0;  // the linear solve's relative tolerance
  int trials = 0;        // line-search trials
  int solves = 0;        // linear solves (> 1: a try failed and was solved again more projected)
  bool exact = false;    // some element Hessian entered unprojected
  int indefinite = 0;    // elements with a negative eigenvalue
  int projected = 0;     // of them, those projected
  double actual = 0;     // the step's decrease of E
  double predicted = 0;  // the decrease its quadratic model predicted (ρ = actual/predicted)
  std::string action;    // the solver's setup action
  // The trust region (xpbd.globalization = trust_region; 0 under the line search):
  double radius = 0;             // Δ of the accepted step
  double ratio = 0;              // its ρ = actual/predicted decrease of E
  bool boundary = false;         // on the region's boundary
  bool negative_curvature = false;  // along a direction of negative curvature (CG's or an element mode)
  int rejected = 0;              // steps rejected before it (ρ ≤ η)
  double shift = 0;              // more_sorensen: σ of K + σK_c
  double curvature = 0;          // the smallest Rayleigh quotient of an element mode in K (< 0: K indefinite)
};

// What the loop shows its caller at every evaluation.
struct NewtonIterate {
  int iteration;
  const Eigen::Matrix3Xd& x;
  const ConstraintState& state;
  const Eigen::VectorXd& lambda;  // −α̃⁻¹C
  const Eigen::Matrix3Xd& g;      // h²∇E per particle (0 at pins; the active bounds' y not zeroed)
  double gradient, gradient0;     // ‖∇E‖ of the free gradient, now and at iteration 0
  double floor;                   // its rounding floor (newton.hpp)
  double energy;
  int active;                     // particles on a plane in the active set (the stop test's)
  int inverted;                   // tets with det F < 0 (ElementHessians::inverted_tets)
  double twist_sum;               // the smallest σ₂ + σ₃ among them (+inf where none)
  const StepRecord& last;
};

struct NewtonHooks {
  std::function<double(int it, double gradient)> tolerance;          // each step's linear tolerance (null: keep)
  std::function<void(const NewtonIterate&)> on_iterate;             // every evaluation (before the stop test)
  std::function<bool()> proceed;                                    // before each step; false: stop (interrupted)
  std::function<bool(const GlobalStepInput&, int it)> on_system;    // true: stop (interrupted; capture)
  std::function<void(const std::string&)> phase;                    // where the loop is (messages)
  int frame = 0, substep = 0;                                       // for the solver's SetupContext
};

struct NewtonOutcome {
  StopReason reason = StopReason::running;
  int iterations = 0;  // steps taken
  double gradient = 0, gradient0 = 0, floor = 0;
  std::string message;  // the solver's, where it failed
};

class NewtonLoop {
 public:
  // prob, ds, step and alpha_tilde must outlive the loop; `step` is a GlobalStep of step = newton.
  NewtonLoop(const Problem& prob, const DualSystem& ds, GlobalStep& step, const Eigen::VectorXd& alpha_tilde, double h,
             const NewtonSettings& s);
  // Minimises E from x̃, or from `start` where given (either projected onto the bounds); x ends
  // at the last iterate.
  NewtonOutcome minimise(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const NewtonHooks& hooks,
                         const Eigen::Matrix3Xd* start = nullptr);
  const ProjectionStrategy& strategy() const { return strategy_; }

 private:
  void evaluate_at(const Eigen::Matrix3Xd& x, ConstraintState& state);
  void evaluate(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);
  // Solves for dx_ (tries until a descent direction or nothing left); false with the reason set.
  bool direction(int it, double relative, const Eigen::Matrix3Xd& x, StepRecord& rec, const NewtonHooks& hooks,
                 NewtonOutcome& out);
  // One step from x (the direction, then the line search, or the trust region's model, subproblem
  // and ratio test), x and the loop's state moved to the accepted point; false with out.reason set.
  bool line_search_step(int it, double gradient, Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, StepRecord& rec,
                        const NewtonHooks& hooks, NewtonOutcome& out);
  // The trust region's models at x: the exact K, the preconditioner, the modes, the first radius.
  bool trust_region_models(int it, const Eigen::Matrix3Xd& x, StepRecord& rec, const NewtonHooks& hooks,
                           NewtonOutcome& out);
  // A step on the models trust_region_models() made at x.
  bool trust_region_step(int it, Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, StepRecord& rec,
                         const NewtonHooks& hooks, NewtonOutcome& out);
  // Whether the models found negative curvature in K (an element mode's Rayleigh quotient < 0):
  // then ‖∇E‖ at its tolerance is a saddle, not a minimiser, and the trust region goes on.
  bool trust_region_saddle() const;
  void accept_trial(Eigen::Matrix3Xd& x, double energy);  // x, state, λ, g ← the trial's
  void make_trust_region();
  void begin_trust_region();  // a new substep: its first iteration sets the radius
  struct TrustRegionState;  // newton_trust_region.cpp
  struct TrustRegionDelete {
    void operator()(TrustRegionState* t) const;
  };

  const Problem& prob_;
  const DualSystem& ds_;
  GlobalStep& step_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  NewtonSettings s_;
  ProjectionStrategy strategy_;
  PlaneBounds bounds_;
  EnergyLineSearch search_;
  ConstraintState state_;
  Eigen::VectorXd lambda_, dlambda_;
  Vector b_;
  Eigen::Matrix3Xd g_, free_g_, dx_, step_taken_;
  double energy_ = 0;
  std::vector<int> active_, held_;  // the active set (stop test), the ε-active set (the step's held y)
  LineSearchTrial trial_;
  bool first_setup_ = true;
  std::unique_ptr<TrustRegionState, TrustRegionDelete> tr_;  // xpbd.globalization = trust_region
};

}  // namespace xb
