// The class behind run_simulation (harness/sim/simulation.hpp), shared by its two files:
// simulation.cpp (the run, the substep loop, the end) and simulation_step.cpp (what is logged per
// evaluation, the method step, Newton's line search). Not for use elsewhere.
#pragma once

#include "global_step.hpp"
#include "forcing.hpp"
#include "reference.hpp"
#include "run_options.hpp"
#include "stability.hpp"

#include "../../problems/dual_system.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/timer.hpp"
#include "../../solvers/local/xpbd_local.hpp"

#include <optional>
#include <string>

namespace xb::detail {

// Runaway: the outer residual grew this much over the substep's first one.
constexpr double divergence_factor = 1e8;

// One run: the method, its state and the log. Algorithm 4 is run() → substep() → the outer loop;
// what is logged per evaluation is in log_state(), the method step in step().
class Simulation {
 public:
  Simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt);
  RunResult run();

 private:
  // What the previous step left for the next log entry.
  struct LastStep {
    LinearStats linear;
    double time = 0;
    double fill = 0;    // s filling A or K (global methods)
    double length = 0;  // step length (global methods)
    double tolerance = 0;  // the linear solve's relative tolerance (global methods)
    int trials = 0;        // line-search trials (step = line_search | newton)
    bool exact = false;    // the step used the exact element Hessians (step = newton, adaptive)
    std::string action;
  };
  // The residuals of one evaluation: the true dual one, the authors', and the stop test's (the
  // dual or the authors' residual, or ‖∇E‖ under step = newton).
  struct Residuals {
    double dual, authors, stop;
  };
  enum class StepEnd { ok, stop, search_failed };
  void substep(int frame, int sub);
  // Past RunOptions::time_budget (less `excluded` s of this substep's reference): fail("timeout").
  bool over_budget(double excluded);
  // Logs the state at iteration `it`; returns the residuals.
  Residuals log_state(int frame, int sub, int it, const LastStep& last);
  void log_linear(const LastStep& last, int it);
  // λ += Δλ, x += (ω or the line search's t)·Δx by Params::step; returns the step length.
  double apply_global_step(LastStep& last);
  // The method step from the state just evaluated (whose stop metric is `residual`).
  StepEnd step(int frame, int sub, int it, double residual, LastStep& last);
  LinearStats global_solve(int frame, int sub, int it, LastStep& last);
  Projection projection(int it) const;
  void check_combination(const std::string& method) const;
  void fail(const std::string& status, const std::string& msg) {
    res_.status = status;
    res_.message = msg;
    stop_ = true;
  }
  void finish();

  const Params& p_;
  const std::string& method_;
  const RunOptions& opt_;
  RunResult res_;
  Timer run_clock_, sub_clock_;
  Problem prob_;
  DualSystem ds_;
  double h_;
  Eigen::VectorXd alpha_tilde_;
  bool newton_;  // step = newton
  std::optional<GlobalStep> global_;
  std::optional<LocalMethod> local_;
  LinearSolver* active_ = nullptr;
  std::optional<ReferenceSolver> reference_;
  StabilityMonitor stability_;
  ForcingRule forcing_;
  Eigen::Matrix3Xd x_pred_, x_old_, dx_, g_, x_ref_;
  double ref_scale_ = 0;  // ‖x_ref − x̃‖_M
  double excluded_ = 0;   // s of the substep spent on the reference and the error, taken off every clock
  double r0_ = 0, stop0_ = 0, newton0_ = 0;  // the substep's first dual, stop and Newton residuals
  double energy_ = 0;     // E at the state just logged
  Eigen::VectorXd lambda_, b_, dlambda_;
  Eigen::VectorXd c_authors_;  // the C of the authors' logged residual (C(x̃) local, C(x_{k−1}) global)
  ConstraintState state_, trial_state_;
  Eigen::Matrix3Xd x_trial_;
  bool first_setup_ = true, stop_ = false, any_max_iterations_ = false;
  int search_failures_ = 0;  // substeps ended by a failed line search on E
  // Where the run is, for an out-of-memory message (std::bad_alloc says nothing).
  std::string phase_ = "the set-up of the run";
  int frame_ = 0, iteration_ = 0;
  int first_frame_ = 0;
};

}  // namespace xb::detail
