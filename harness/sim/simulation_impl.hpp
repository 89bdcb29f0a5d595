// The class behind run_simulation (harness/sim/simulation.hpp), shared by its two files:
// simulation.cpp (the run, the substep loop, the end) and simulation_step.cpp (what is logged per
// evaluation, the method step, Newton's line search). Not for use elsewhere.
#pragma once

#include "block_descent.hpp"
#include "global_step.hpp"
#include "forcing.hpp"
#include "newton_loop.hpp"
#include "reference.hpp"
#include "reference_store.hpp"
#include "run_options.hpp"
#include "stability.hpp"

#include "../../problems/dual_system.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/timer.hpp"
#include "../../solvers/local/xpbd_local.hpp"

#include <optional>
#include <string>

namespace xb::detail {

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
  // Before every outer iteration: a resident set past RunOptions::memory_limit:
  // fail("out_of_memory"); else over_time.
  bool over_budget(double excluded);
  // Past RunOptions::time_budget (less `excluded` s of this substep's reference): fail("over_budget").
  bool over_time(double excluded);
  // This substep's reference: read from the store where it holds it, else computed (and stored).
  ReferenceSolution solve_reference(int frame, int sub);
  // The outer loop of step = newton: the one Newton loop (newton_loop.hpp) with the stepper's hooks.
  void newton_substep(int frame, int sub);
  void xpbd_substep(int frame, int sub);
  // The outer loop of vbd and avbd: the block-descent loop (block_descent.hpp) with the stepper's hooks.
  void block_descent_substep(int frame, int sub);
  // Logs the state at iteration `it` (XPBD's methods: evaluates it); returns the residuals.
  Residuals log_state(int frame, int sub, int it, const LastStep& last);
  void log_entry(int frame, int sub, int it, const Entry& e, const LastStep& last);
  void log_linear(const LastStep& last, int it);
  void log_trust_region(const LastStep& s);  // xpbd.globalization = trust_region's entries
  // λ += Δλ, x += (ω or the line search's t)·Δx by Params::step; returns the step length.
  double apply_global_step(LastStep& last);
  // The substep's reference and its certificate into the log (the reference/ group).
  void log_reference(const ReferenceSolution& rs);
  // Ends the substep: the count of its stop reason, `substep_status` and `substep_success`.
  void end_substep(StopReason reason);
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

  // What the run is: its settings, its copy of the problem, the substep's h and α̃.
  const Params& p_;
  const std::string& method_;
  const RunOptions& opt_;
  // The clocks, started first (the run's covers its set-up): the run's, the substep's, and the
  // reference's share of the substep.
  struct Clocks {
    Timer run, sub;
    double excluded = 0;  // s of the substep spent on the reference and the error, taken off every clock
  } clock_;
  Problem prob_;
  DualSystem ds_;
  double h_;
  Eigen::VectorXd alpha_tilde_;
  bool newton_;  // step = newton

  // The method: the outer loop's step (global linear step, Newton loop or local sweep) and its rules.
  struct Method {
    explicit Method(const LinearSettings& linear) : forcing(linear) {}
    std::optional<GlobalStep> global;
    std::optional<NewtonLoop> newton;  // step = newton: the one Newton loop on `global`
    std::optional<LocalMethod> local;
    std::optional<BlockDescentLoop> block;  // vbd, avbd
    LinearSolver* active = nullptr;    // the global step's solver (its statistics)
    ForcingRule forcing;
    StopCriterion criterion;           // XPBD's outer loop (Newton's is its loop's)
    Projection projection = Projection::clamp;  // xpbd.hessian_projection under XPBD (clamp | abs)
    bool first_setup = true;
  } m_;

  // The truth: each substep's reference and what the position error is measured against.
  struct Truth {
    std::optional<ReferenceSolver> solver;  // made at the first reference not read from the store
    std::optional<ReferenceStore> store;    // RunOptions::reference_file
    Eigen::Matrix3Xd x;  // x_ref
    double scale = 0;    // position_error's denominator (ReferenceSolution::error_scale)
  } truth_;

  // The substep: x̃, its start, and XPBD's outer-loop state (Newton's is its loop's).
  struct Substep {
    Eigen::Matrix3Xd x_pred, x_old, v_old;  // v_old: before gravity's kick
    Eigen::VectorXd lambda, b, dlambda;
    Eigen::Matrix3Xd dx, g, x_trial;
    ConstraintState state, trial_state;
    Eigen::VectorXd c_authors;     // the C of the authors' logged residual (C(x̃) local, C(x_{k−1}) global)
    double r0 = 0, newton0 = 0;    // the substep's first dual and Newton residuals
    double energy = 0;             // E at the state just logged
  } substep_;

  // The outcome: the result and log, how the substeps ended, the stability checks, the stop flag.
  RunResult res_;
  struct Ends {
    int max_iterations = 0;
    int search_failures = 0;  // substeps ended by a failed line search on E
    int search_at_floor = 0;  // of them, those within 1e2 of the rounding floor (line_search_at_floor)
    int region_failures = 0;  // substeps ended by a collapsed trust region
    int region_at_floor = 0;  // of them, those within 1e2 of the rounding floor (trust_region_at_floor)
    int rounding_floor = 0;   // substeps ended at the rounding floor of ‖∇E‖
  } ends_;
  StabilityMonitor stability_;
  bool stop_ = false;

  // Where the run is, for an out-of-memory message (std::bad_alloc says nothing).
  struct Where {
    std::string phase = "the set-up of the run";
    int frame = 0, iteration = 0, first_frame = 0;
  } where_;
};

}  // namespace xb::detail
