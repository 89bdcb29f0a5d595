// The class behind run_simulation (harness/sim/simulation.hpp), shared by its two files:
// simulation.cpp (the run, the substep loop, the end) and simulation_step.cpp (what is logged per
// evaluation, the method step, Newton's line search). Not for use elsewhere.
#pragma once

#include "global_step.hpp"
#include "forcing.hpp"
#include "newton_loop.hpp"
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
  // What the previous step left for the next log entry (newton_loop.hpp).
  using LastStep = StepRecord;
  // The residuals of one evaluation: the true dual one, the authors', and the stop test's (the
  // dual or the authors' residual).
  struct Residuals {
    double dual, authors, stop;
  };
  // One log entry's values (what log_state evaluates, or a Newton iterate shows).
  struct Entry {
    double dual, authors, primal, energy;
  };
  enum class StepEnd { ok, stop };
  void substep(int frame, int sub);
  // Past RunOptions::time_budget (less `excluded` s of this substep's reference): fail("timeout").
  bool over_budget(double excluded);
  // The outer loop of step = newton: the one Newton loop (newton_loop.hpp) with the stepper's hooks.
  void newton_substep(int frame, int sub);
  void xpbd_substep(int frame, int sub);
  // Logs the state at iteration `it` (XPBD's methods: evaluates it); returns the residuals.
  Residuals log_state(int frame, int sub, int it, const LastStep& last);
  void log_entry(int frame, int sub, int it, const Entry& e, const LastStep& last);
  void log_linear(const LastStep& last, int it);
  void log_trust_region(const LastStep& s);  // xpbd.globalization = trust_region's entries
  // λ += Δλ, x += (ω or the line search's t)·Δx by Params::step; returns the step length.
  double apply_global_step(LastStep& last);
  // Ends the substep: the count of its status and `substep_status`.
  void end_substep(const std::string& status);
  // The method step from the state just evaluated (whose stop metric is `residual`).
  StepEnd step(int frame, int sub, int it, double residual, LastStep& last);
  LinearStats global_solve(int frame, int sub, int it, LastStep& last);
  void check_combination(const std::string& method) const;
  void check_globalization(const std::string& method) const;
  void fail(const std::string& status, const std::string& msg) {
    res_.status = status;
    res_.message = msg;
    stop_ = true;
  }
  void finish();
  // A run whose reference did not converge says so in its status and message (docs/newton.md).
  void reference_verdict();

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
  std::optional<NewtonLoop> newton_loop_;  // step = newton
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
  bool first_setup_ = true, stop_ = false;
  int max_iteration_substeps_ = 0;
  int search_failures_ = 0;  // substeps ended by a failed line search on E
  int region_failures_ = 0;  // substeps ended by a collapsed trust region
  int rounding_floor_ = 0;   // substeps ended at the rounding floor of ‖∇E‖
  // Where the run is, for an out-of-memory message (std::bad_alloc says nothing).
  std::string phase_ = "the set-up of the run";
  int frame_ = 0, iteration_ = 0;
  int first_frame_ = 0;
};

}  // namespace xb::detail
