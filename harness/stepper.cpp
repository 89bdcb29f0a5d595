#include "stepper.hpp"

#include "stability.hpp"

#include "primal_solve.hpp"
#include "reference.hpp"

#include "../problems/dual_system.hpp"
#include "../problems/error.hpp"
#include "../solvers/linear_solver.hpp"
#include "../solvers/timer.hpp"
#include "../solvers/xpbd_local.hpp"

#include <omp.h>

#include <cmath>
#include <memory>
#include <optional>

namespace xb {

namespace {

// Runaway: the dual residual grew this much over the substep's first one.
constexpr double divergence_factor = 1e8;

double primal_residual(const Problem& prob, const DualSystem& ds, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& lambda, Eigen::Matrix3Xd& work) {
  ds.apply_gradT(s, lambda, work);
  const Eigen::VectorXd& w = prob.particles.w;
  double sum = 0;
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w[p] > 0) sum += ((x.col(p) - x_pred.col(p)) / w[p] - work.col(p)).squaredNorm();
  return std::sqrt(sum);
}

double incremental_energy(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                          const Eigen::Matrix3Xd& x_pred, double h) {
  const Eigen::VectorXd& w = prob.particles.w;
  double kin = 0, pot = 0;
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w[p] > 0) kin += (x.col(p) - x_pred.col(p)).squaredNorm() / w[p];
  for (int j = 0; j < prob.num_constraints(); ++j) {
    const double a = prob.compliance(j);
    if (a > 0) pot += s.C[j] * s.C[j] / a;
  }
  return kin / (2 * h * h) + pot / 2;
}

void project_colliders(const Problem& prob, Eigen::Matrix3Xd& x) {
  for (const auto& plane : prob.planes)
    for (int p = 0; p < static_cast<int>(x.cols()); ++p)
      if (prob.particles.w[p] > 0 && x(1, p) < plane.height) x(1, p) = plane.height;
}

}  // namespace

RunResult run_simulation(const Problem& prob_in, const Params& p, const std::string& method, const RunOptions& opt) {
  const MethodInfo* info = find_method(method);
  if (!info) (void)make_linear_solver(method, p);  // throws with the valid names
  if (!info->available) throw Error("solver '" + method + "' is not available: " + info->reason);
  if (p.threads > 0) omp_set_num_threads(p.threads);

  RunResult res;
  Timer run_clock;
  Problem prob = prob_in;
  DualSystem ds(prob);
  const int m = prob.num_constraints();
  const double h = p.dt / p.substeps;
  const Eigen::VectorXd alpha_tilde = scaled_compliance(prob, h);
  std::unique_ptr<LinearSolver> solver;  // the dual form's
  std::optional<PrimalSolve> primal;     // or the primal form's
  std::optional<LocalMethod> local;
  std::optional<ReferenceSolver> reference;
  if (opt.reference) {
    Timer ref_clock;
    reference.emplace(prob, p);
    res.reference_time += ref_clock.seconds();
  }
  Eigen::Matrix3Xd x_ref;
  double ref_scale = 0;  // ‖x_ref − x̃‖_M
  if (info->local) {
    local.emplace(prob, ds, p, method == "xpbd-gs");
    res.form_used = "none";
  } else {
    res.form_used = resolve_form(p.form, alpha_tilde);
    if (res.form_used == "primal")
      primal.emplace(make_linear_solver(method, p), constraint_graph(prob), p.linear_tol);
    else
      solver = make_linear_solver(method, p);
  }
  LinearSolver* active = primal ? &primal->solver() : solver.get();

  Particles& P = prob.particles;
  StabilityMonitor stability(prob, p);  // after every substep: nan, runaway, inverted tets
  Eigen::Matrix3Xd x_pred, x_old, dx, work;
  Eigen::VectorXd lambda(m), b(m), dlambda;
  ConstraintState state;
  IterationLog& L = res.log;
  bool first_setup = true;
  bool stop = false;
  bool any_max_iterations = false;

  auto fail = [&](const std::string& status, const std::string& msg) {
    res.status = status;
    res.message = msg;
    stop = true;
  };

  try {
    for (int frame = 0; frame < p.frames && !stop; ++frame) {
      for (int sub = 0; sub < p.substeps && !stop; ++sub) {
        Timer sub_clock;
        x_old = P.x;
        for (int i = 0; i < P.size(); ++i)
          if (P.w[i] > 0) P.v.col(i) += h * prob.gravity;
        x_pred = P.x + h * P.v;
        for (int i = 0; i < P.size(); ++i)
          if (P.w[i] == 0) x_pred.col(i) = P.x.col(i);  // pins stay
        P.x = x_pred;
        lambda.setZero();
        // Time spent on the reference and the error is taken off every clock of the run.
        double excluded = 0;
        if (reference) {
          Timer ref_clock;
          ReferenceSolution rs = reference->solve(x_pred, alpha_tilde);
          x_ref = std::move(rs.x);
          ref_scale = mass_norm_distance(prob, x_ref, x_pred);
          L.reference_relative_dual_residual.push_back(rs.relative_dual_residual);
          L.reference_iterations.push_back(rs.iterations);
          L.reference_status.push_back(rs.status);
          excluded += ref_clock.seconds();
        }
        double r0 = 0;
        bool converged = false;
        LinearStats last_linear;
        double last_step_time = 0;
        std::string last_action;
        ++res.substeps_total;
        for (int it = 0;; ++it) {
          evaluate_constraints(prob, P.x, state);
          b = -(state.C + alpha_tilde.cwiseProduct(lambda));
          const double dual = b.norm();
          if (it == 0) r0 = dual;
          // Log this state.
          L.frame.push_back(frame);
          L.substep.push_back(sub);
          L.iteration.push_back(it);
          L.dual_residual.push_back(dual);
          L.relative_dual_residual.push_back(r0 > 0 ? dual / r0 : 0);
          L.primal_residual.push_back(primal_residual(prob, ds, state, P.x, x_pred, lambda, work));
          L.energy.push_back(incremental_energy(prob, state, P.x, x_pred, h));
          if (reference) {
            Timer err_clock;
            const double e = mass_norm_distance(prob, P.x, x_ref);
            // A substep whose reference does not move (x_ref = x̃) has no scale: absolute error.
            L.position_error.push_back(ref_scale > 0 ? e / ref_scale : e);
            excluded += err_clock.seconds();
          }
          L.wall_time.push_back(sub_clock.seconds() - excluded);
          L.step_time.push_back(it == 0 ? 0 : last_step_time);
          L.linear_iterations.push_back(it == 0 ? 0 : last_linear.iterations);
          L.linear_setup_time.push_back(it == 0 ? 0 : last_linear.setup_time);
          L.linear_solve_time.push_back(it == 0 ? 0 : last_linear.solve_time);
          L.linear_relative_residual.push_back(it == 0 ? 0 : last_linear.final_relative_residual);
          L.linear_setup_action.push_back(it == 0 ? "" : last_action);
          if (it > 0) {
            L.linear_history_residual.insert(L.linear_history_residual.end(), last_linear.residual_history.begin(),
                                             last_linear.residual_history.end());
            L.linear_history_time.insert(L.linear_history_time.end(), last_linear.residual_time.begin(),
                                         last_linear.residual_time.end());
          }
          L.linear_history_offset.push_back(static_cast<long long>(L.linear_history_residual.size()));
          res.final_dual_residual = dual;
          res.relative_dual_residual = r0 > 0 ? dual / r0 : 0;

          if (!std::isfinite(dual) || !P.x.allFinite()) {
            fail("nan", "non-finite positions or dual residual at frame " + std::to_string(frame) + ", iteration " +
                            std::to_string(it));
            break;
          }
          if (dual > divergence_factor * r0 && dual > p.atol) {
            fail("diverged", "dual residual grew by more than 1e8 over its first value at frame " +
                                 std::to_string(frame) + ", iteration " + std::to_string(it));
            break;
          }
          if (dual <= p.rtol * r0 || dual <= p.atol) {
            converged = true;
            break;
          }
          if (it >= p.max_iterations) break;
          if (opt.time_budget > 0 && run_clock.seconds() - res.reference_time - excluded > opt.time_budget) {
            fail("timeout", "time budget of " + std::to_string(opt.time_budget) + " s exceeded");
            break;
          }

          // The method step.
          Timer step_clock;
          if (local) {
            local->sweep(P.x, lambda, alpha_tilde, state);
            last_linear = LinearStats{};
            last_action = "";
          } else {
            if (!primal || opt.on_system) ds.fill(state, alpha_tilde);
            if (opt.on_system && opt.on_system(SystemView{frame, sub, it, ds.A(), b, state, alpha_tilde, P.x})) {
              stop = true;
              res.message = "stopped by capture";
              break;
            }
            const SetupKind kind = first_setup ? SetupKind::Structure : SetupKind::Values;
            first_setup = false;
            if (primal) {
              primal->setup(state.grad, alpha_tilde, P.x, kind, SetupContext{frame, sub, it});
              last_linear = primal->solve(b, dlambda);
            } else {
              solver->setup(ds.A(), kind, SetupContext{frame, sub, it});
              last_linear = solver->solve(b, dlambda);
            }
            last_action = active->last_setup_action();
            if (last_linear.status == LinearStatus::breakdown) {
              fail("breakdown", "linear solver " + method + " broke down at frame " + std::to_string(frame) +
                                    ", iteration " + std::to_string(it) + ": " + last_linear.message);
              break;
            }
            lambda += dlambda;
            ds.apply_minv_gradT(state, dlambda, dx);
            P.x += p.omega * dx;
          }
          project_colliders(prob, P.x);
          last_step_time = step_clock.seconds();
          ++res.outer_iterations;
        }
        res.reference_time += excluded;
        if (stop) break;
        if (converged)
          ++res.substeps_converged;
        else
          any_max_iterations = true;
        project_colliders(prob, P.x);
        P.v = (P.x - x_old) / h;
        if (std::string st, msg; !stability.check(P, frame, sub, st, msg)) {
          fail(st, msg);
          break;
        }
      }
      if (!stop && opt.on_frame) opt.on_frame(frame, P.x);
    }
  } catch (const std::exception& e) {
    fail("error", e.what());
  }
  if (res.status == "ok" && any_max_iterations) {
    res.status = "max_iterations";
    res.message = std::to_string(res.substeps_total - res.substeps_converged) + " of " +
                  std::to_string(res.substeps_total) + " substeps stopped at max_iterations";
  }
  res.wall_time = run_clock.seconds() - res.reference_time;
  if (active) {
    res.stats = active->statistics();
    res.arrays = active->array_statistics();
  }
  if (local && method == "xpbd-gs") res.stats["colors"] = local->num_colors();
  if (local && method == "xpbd-jacobi") res.stats["jacobi_relaxation_used"] = local->relaxation();
  // Datasets that apply to this scene only: inverted tets per substep (tet scenes), the edge
  // list and rest lengths (distance constraints: plots/cloth_stretch.py colours edges by stretch).
  if (stability.has_tets()) res.arrays["inverted_tets"] = stability.inverted_tets();
  if (prob.distance.size() > 0) {
    std::vector<double> edges;
    edges.reserve(2 * prob.distance.size());
    for (const auto& e : prob.distance.idx) edges.insert(edges.end(), {double(e[0]), double(e[1])});
    res.arrays["distance_edges"] = std::move(edges);
    res.arrays["distance_rest_length"] = prob.distance.rest_length;
  }
  res.stats["rows"] = m;
  res.stats["nonzeros"] = static_cast<double>(ds.A().nonZeros());
  if (primal) {
    res.stats["primal_rows"] = primal->system().rows();
    res.stats["primal_nonzeros"] = static_cast<double>(primal->system().K().nonZeros());
  }
  res.stats["particles"] = P.size();
  res.final_positions = P.x;
  return res;
}

}  // namespace xb
