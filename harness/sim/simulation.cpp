#include "simulation.hpp"

#include "forcing.hpp"
#include "line_search.hpp"
#include "primal_solve.hpp"
#include "reference.hpp"
#include "residual_energy.hpp"
#include "stability.hpp"

#include "../../problems/dual_system.hpp"
#include "../../core/error.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/timer.hpp"
#include "../../solvers/local/xpbd_local.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <new>
#include <optional>

namespace xb {

namespace {

// Runaway: the dual residual grew this much over the substep's first one.
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
    std::string action;
  };
  // The two residuals of one evaluation: the true one and the authors' (IterationLog).
  struct Residuals {
    double dual, authors;
  };
  void substep(int frame, int sub);
  // Past RunOptions::time_budget (less `excluded` s of this substep's reference): fail("timeout").
  bool over_budget(double excluded);
  // Logs the state at iteration `it`; returns both residuals.
  Residuals log_state(int frame, int sub, int it, const LastStep& last, double& r0);
  // λ += Δλ, x += (ω or the line search's t)·Δx by Params::step; returns the step length.
  double apply_global_step();
  // The method step from the state just evaluated (whose stop metric is `residual`); false if
  // the run must stop.
  bool step(int frame, int sub, int it, double residual, LastStep& last);
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
  std::unique_ptr<LinearSolver> solver_;  // the dual form's
  std::optional<PrimalSolve> primal_;     // or the primal form's
  std::optional<LocalMethod> local_;
  LinearSolver* active_ = nullptr;
  std::optional<ReferenceSolver> reference_;
  StabilityMonitor stability_;
  ForcingRule forcing_;
  Eigen::Matrix3Xd x_pred_, x_old_, dx_, work_, x_ref_;
  double ref_scale_ = 0;  // ‖x_ref − x̃‖_M
  double excluded_ = 0;   // s of the substep spent on the reference and the error, taken off every clock
  Eigen::VectorXd lambda_, b_, dlambda_;
  Eigen::VectorXd c_authors_;  // the C of the authors' logged residual (C(x̃) local, C(x_{k−1}) global)
  ConstraintState state_, trial_state_;
  Eigen::Matrix3Xd x_trial_;
  bool first_setup_ = true, stop_ = false, any_max_iterations_ = false;
  // Where the run is, for an out-of-memory message (std::bad_alloc says nothing).
  std::string phase_ = "the set-up of the run";
  int frame_ = 0, iteration_ = 0;
  int first_frame_ = 0;
};

Simulation::Simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt)
    : p_(p), method_(method), opt_(opt), prob_(prob), ds_(prob_), h_(p.dt / p.substeps),
      alpha_tilde_(scaled_compliance(prob_, h_)), stability_(prob_, p),
      forcing_(p.linear) {
  if (opt.reference) {
    Timer ref_clock;
    reference_.emplace(prob_, p);
    res_.reference_method = reference_method_description();
    res_.reference_time += ref_clock.seconds();
  }
  if (find_method(method)->local) {
    local_.emplace(prob_, ds_, p.xpbd, local_kind(method));
    res_.form_used = "none";
  } else {
    res_.form_used = resolve_form(p.form, alpha_tilde_);
    if (res_.form_used == "primal")
      primal_.emplace(make_linear_solver(method, p), constraint_graph(prob_), p.linear);
    else
      solver_ = make_linear_solver(method, p);
    active_ = primal_ ? &primal_->solver() : solver_.get();
  }
  lambda_.resize(prob_.num_constraints());
}

RunResult Simulation::run() {
  try {
    int start = 0;
    if (const SimState* s = opt_.initial_state) {
      if (s->x.cols() != prob_.particles.size() || s->v.cols() != prob_.particles.size())
        throw Error("the loaded state has " + std::to_string(s->x.cols()) + " particles, the scene " +
                    std::to_string(prob_.particles.size()));
      prob_.particles.x = s->x;
      prob_.particles.v = s->v;
      start = s->frame;
    }
    first_frame_ = start;
    for (int frame = start; frame < start + p_.frames && !stop_; ++frame) {
      for (int sub = 0; sub < p_.substeps && !stop_; ++sub) substep(frame, sub);
      if (!stop_ && opt_.on_frame) opt_.on_frame(frame, prob_.particles.x);
      if (!stop_ && opt_.on_state) opt_.on_state(SimState{frame + 1, prob_.particles.x, prob_.particles.v});
    }
  } catch (const std::bad_alloc&) {
    fail("error", "out of memory in " + phase_ + " at frame " + std::to_string(frame_) + ", iteration " +
                      std::to_string(iteration_));
  } catch (const std::exception& e) {
    fail("error", e.what());
  }
  finish();
  return std::move(res_);
}

// Checked every outer iteration and every substep, so that no count of either escapes it.
bool Simulation::over_budget(double excluded) {
  if (opt_.time_budget <= 0 || run_clock_.seconds() - res_.reference_time - excluded <= opt_.time_budget) return false;
  char budget[32];
  std::snprintf(budget, sizeof budget, "%g", opt_.time_budget);
  fail("timeout", std::string("time budget of ") + budget + " s exceeded");
  return true;
}

void Simulation::substep(int frame, int sub) {
  if (over_budget(0)) return;
  Particles& P = prob_.particles;
  sub_clock_.reset();
  x_old_ = P.x;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) P.v.col(i) += h_ * prob_.gravity;
  x_pred_ = P.x + h_ * P.v;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] == 0) x_pred_.col(i) = P.x.col(i);  // pins stay
  P.x = x_pred_;
  lambda_.setZero();
  excluded_ = 0;
  if (reference_) {
    Timer ref_clock;
    ReferenceSolution rs = reference_->solve(x_pred_, alpha_tilde_);
    x_ref_ = std::move(rs.x);
    ref_scale_ = mass_norm_distance(prob_, x_ref_, x_pred_);
    res_.log.reference_relative_dual_residual.push_back(rs.relative_dual_residual);
    res_.log.reference_iterations.push_back(rs.iterations);
    res_.log.reference_status.push_back(rs.status);
    excluded_ += ref_clock.seconds();
  }
  ++res_.substeps_total;
  double r0 = 0;
  bool converged = false;
  LastStep last;
  const bool authors_stop = p_.residual_metric == "authors";
  for (int it = 0;; ++it) {
    frame_ = frame;
    iteration_ = it;
    phase_ = "the constraint evaluation";
    const Residuals r = log_state(frame, sub, it, last, r0);
    if (opt_.on_iteration)
      opt_.on_iteration({frame, first_frame_, p_.frames, sub, p_.substeps, it, p_.max_iterations, r0 > 0 ? r.dual / r0 : 0});
    const double dual = r.dual;
    const double stop_metric = authors_stop ? r.authors : dual;  // r0 is the same for both
    const std::string where = " at frame " + std::to_string(frame) + ", iteration " + std::to_string(it);
    if (!std::isfinite(dual) || !P.x.allFinite()) {
      fail("nan", "non-finite positions or dual residual" + where);
      break;
    }
    if (dual > divergence_factor * r0 && dual > p_.atol) {
      fail("diverged", "dual residual grew by more than 1e8 over its first value" + where);
      break;
    }
    if (stop_metric <= p_.rtol * r0 || stop_metric <= p_.atol) {
      converged = true;
      break;
    }
    if (it >= p_.max_iterations) break;
    if (over_budget(excluded_)) break;
    Timer step_clock;
    if (!step(frame, sub, it, dual, last)) break;  // the forcing rule reads the dual residual
    project_onto_planes(prob_, P.x);
    last.time = step_clock.seconds();
    ++res_.outer_iterations;
  }
  res_.reference_time += excluded_;
  if (stop_) return;
  if (converged)
    ++res_.substeps_converged;
  else
    any_max_iterations_ = true;
  project_onto_planes(prob_, P.x);
  P.v = (P.x - x_old_) / h_;
  if (std::string st, msg; !stability_.check(P, frame, sub, st, msg)) fail(st, msg);
}

Simulation::Residuals Simulation::log_state(int frame, int sub, int it, const LastStep& last, double& r0) {
  const Particles& P = prob_.particles;
  if (it > 0 && !local_) c_authors_ = state_.C;  // global: C(x_{k−1}), before it is re-evaluated
  evaluate_constraints(prob_, P.x, state_);
  if (it == 0) c_authors_ = state_.C;  // C(x̃); local methods keep it for the whole substep
  b_ = -(state_.C + alpha_tilde_.cwiseProduct(lambda_));
  const double dual = b_.norm();
  const double authors = (c_authors_ + alpha_tilde_.cwiseProduct(lambda_)).norm();
  if (it == 0) r0 = dual;
  IterationLog& L = res_.log;
  L.frame.push_back(frame);
  L.substep.push_back(sub);
  L.iteration.push_back(it);
  L.dual_residual.push_back(dual);
  L.relative_dual_residual.push_back(r0 > 0 ? dual / r0 : 0);
  L.authors_dual_residual.push_back(authors);
  L.authors_relative_dual_residual.push_back(r0 > 0 ? authors / r0 : 0);
  L.primal_residual.push_back(primal_residual(prob_, ds_, state_, P.x, x_pred_, lambda_, work_));
  L.energy.push_back(incremental_energy(prob_, state_, P.x, x_pred_, h_));
  if (reference_) {
    Timer err_clock;
    const double e = mass_norm_distance(prob_, P.x, x_ref_);
    // A substep whose reference does not move (x_ref = x̃) has no scale: absolute error.
    L.position_error.push_back(ref_scale_ > 0 ? e / ref_scale_ : e);
    excluded_ += err_clock.seconds();
  }
  L.wall_time.push_back(sub_clock_.seconds() - excluded_);
  // The linear_* entries describe the step that led here (none at iteration 0).
  const LastStep none;
  const LastStep& s = it == 0 ? none : last;
  L.step_time.push_back(s.time);
  L.fill_time.push_back(s.fill);
  L.step_length.push_back(s.length);
  L.linear_iterations.push_back(s.linear.iterations);
  L.linear_setup_time.push_back(s.linear.setup_time);
  L.linear_solve_time.push_back(s.linear.solve_time);
  L.linear_relative_residual.push_back(s.linear.final_relative_residual);
  L.linear_tolerance.push_back(s.tolerance);
  L.linear_setup_action.push_back(s.action);
  L.linear_history_residual.insert(L.linear_history_residual.end(), s.linear.residual_history.begin(),
                                   s.linear.residual_history.end());
  L.linear_history_time.insert(L.linear_history_time.end(), s.linear.residual_time.begin(), s.linear.residual_time.end());
  L.linear_history_offset.push_back(static_cast<long long>(L.linear_history_residual.size()));
  res_.final_dual_residual = dual;
  res_.relative_dual_residual = r0 > 0 ? dual / r0 : 0;
  res_.stats["final_authors_dual_residual"] = authors;
  return {dual, authors};
}

bool Simulation::step(int frame, int sub, int it, double residual, LastStep& last) {
  Particles& P = prob_.particles;
  if (local_) {
    local_->sweep(P.x, lambda_, alpha_tilde_, state_);
    last.linear = LinearStats{};
    last.action = "";
    return true;
  }
  if (!primal_ || opt_.on_system) {  // the primal form fills K instead (capture needs A too)
    phase_ = "the fill of A";
    Timer fill_clock;
    ds_.fill(state_, alpha_tilde_);
    last.fill = fill_clock.seconds();
  }
  if (opt_.on_system && opt_.on_system(SystemView{frame, sub, it, ds_.A(), b_, state_, alpha_tilde_, P.x})) {
    stop_ = true;
    res_.message = "stopped by capture";
    return false;
  }
  const SetupKind kind = first_setup_ ? SetupKind::Structure : SetupKind::Values;
  first_setup_ = false;
  last.tolerance = forcing_.next(it, residual);
  if (primal_)
    primal_->set_tolerance(last.tolerance);
  else
    solver_->set_tolerance(last.tolerance);
  phase_ = "the setup of " + method_ + (primal_ ? " (primal form, K's fill included)" : "");
  if (primal_)
    primal_->setup(state_.grad, alpha_tilde_, P.x, kind, SetupContext{frame, sub, it});
  else
    solver_->setup(ds_.A(), kind, SetupContext{frame, sub, it});
  if (primal_) last.fill = primal_->fill_time();
  phase_ = "the solve of " + method_;
  last.linear = primal_ ? primal_->solve(b_, dlambda_) : solver_->solve(b_, dlambda_);
  phase_ = "the step";
  last.action = active_->last_setup_action();
  if (last.linear.status == LinearStatus::breakdown) {
    fail("breakdown", "linear solver " + method_ + " broke down at frame " + std::to_string(frame) + ", iteration " +
                          std::to_string(it) + ": " + last.linear.message);
    return false;
  }
  last.length = apply_global_step();
  return true;
}

double Simulation::apply_global_step() {
  Particles& P = prob_.particles;
  ds_.apply_minv_gradT(state_, dlambda_, dx_);
  if (p_.step == "line_search") {
    lambda_ += dlambda_;
    const double current = (state_.C + alpha_tilde_.cwiseProduct(lambda_)).norm();  // C(x) with the new λ
    const LineSearchStep ls = backtrack_dual_residual(prob_, P.x, lambda_, dx_, alpha_tilde_, current,
                                                      trial_state_, x_trial_);
    P.x += ls.t * dx_;
    return ls.t;
  }
  lambda_ += dlambda_;
  P.x += p_.omega * dx_;
  return p_.omega;
}

void Simulation::finish() {
  if (res_.status == "ok" && any_max_iterations_) {
    res_.status = "max_iterations";
    res_.message = std::to_string(res_.substeps_total - res_.substeps_converged) + " of " +
                   std::to_string(res_.substeps_total) + " substeps stopped at max_iterations";
  }
  res_.wall_time = run_clock_.seconds() - res_.reference_time;
  if (active_) {
    res_.stats = active_->statistics();
    res_.arrays = active_->array_statistics();
  }
  if (local_)
    for (const auto& [key, value] : local_->statistics()) res_.stats[key] = value;
  // Datasets that apply to this scene only: inverted tets per substep (tet scenes), the edge
  // list and rest lengths (distance constraints: plots/cloth_stretch.py colours edges by stretch).
  if (stability_.has_tets()) res_.arrays["inverted_tets"] = stability_.inverted_tets();
  if (prob_.distance.size() > 0) {
    std::vector<double> edges;
    edges.reserve(2 * prob_.distance.size());
    for (const auto& e : prob_.distance.idx) edges.insert(edges.end(), {double(e[0]), double(e[1])});
    res_.arrays["distance_edges"] = std::move(edges);
    res_.arrays["distance_rest_length"] = prob_.distance.rest_length;
  }
  res_.stats["rows"] = prob_.num_constraints();
  res_.stats["nonzeros"] = static_cast<double>(ds_.A().nonZeros());
  if (primal_) {
    res_.stats["primal_rows"] = primal_->system().rows();
    res_.stats["primal_nonzeros"] = static_cast<double>(primal_->system().K().nonZeros());
  }
  res_.stats["particles"] = prob_.particles.size();
  res_.final_positions = prob_.particles.x;
}

}  // namespace

RunResult run_simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt) {
  const MethodInfo* info = find_method(method);
  if (!info) (void)make_linear_solver(method, p);  // throws with the valid names
  if (!info->available) throw Error("solver '" + method + "' is not available: " + info->reason);
  if (p.threads > 0) omp_set_num_threads(p.threads);
  try {
    return Simulation(prob, p, method, opt).run();
  } catch (const std::bad_alloc&) {  // the run's copies of the problem and its systems
    RunResult r;
    r.status = "error";
    r.message = "out of memory in the set-up of the run (" + method + ": the problem's copy, A's pattern, the solver)";
    return r;
  }
}

}  // namespace xb
