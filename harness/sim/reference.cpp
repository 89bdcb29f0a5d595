#include "reference.hpp"

#include "newton.hpp"
#include "newton_loop.hpp"
#include "residual_energy.hpp"

#include "../../core/error.hpp"
#include "../../core/reduce.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace xb {

std::string resolve_reference_method(const std::string& requested, const Eigen::VectorXd& alpha_tilde) {
  const bool compliant = (alpha_tilde.array() > 0).all();
  if (requested == "auto") return compliant ? "newton" : "xpbd";
  if (requested == "newton" && !compliant)
    throw Error("reference.method=newton needs every constraint compliant (alpha~ > 0): E(x) has no term for a "
                "rigid constraint (use reference.method=xpbd)");
  return requested;
}

std::string reference_description(const Params& p, const Eigen::VectorXd& alpha_tilde) {
  if (resolve_reference_method(p.reference_method, alpha_tilde) == "newton") {
    const std::string linear = p.reference_linear == "cholmod"
                                   ? std::string("cholmod")
                                   : p.reference_linear + " (eisenstat_walker down to 1e-12)";
    const std::string until = ", the ground planes as bounds (projected Newton), from x~, until |grad E| (free) <= 1e-10 "
                              "of its value at x~ or at its rounding floor, at most 100 iterations; the iterate with the "
                              "smallest |grad E| is the reference";
    if (p.reference_globalization == "trust_region")
      return "newton: Newton's method on E(x) (the backward-Euler solution of the substep) by the stepper's Newton "
             "loop with a trust region on the exact Hessian (subproblem " + p.reference_trust_region_subproblem + ", " +
             linear + " on the primal form)" + until;
    return "newton: Newton's method on E(x) (the backward-Euler solution of the substep) by the stepper's Newton "
           "loop, " + linear + " on the primal form with the full geometric stiffness (xpbd.hessian_projection = " +
           ReferenceSolver::projection + "), robust Armijo backtracking on E" + until;
  }
  return "xpbd: cholmod (global direct solve of A dlambda = -(C + alpha~ lambda)), omega = 1, from the substep's "
         "predicted state x~ with lambda = 0, recomputed every substep from the run's own state; stops at a dual "
         "residual of 1e-10 relative or when it stops improving (no 1% gain in 5 iterations), at most 100 "
         "iterations; the best iterate is the reference";
}

ReferenceSolver::ReferenceSolver(const Problem& prob, const Params& p, const Eigen::VectorXd& alpha_tilde,
                                 const ReferenceSettings& settings)
    : prob_(prob), alpha_tilde_(alpha_tilde), h_(p.dt / p.substeps),
      method_(resolve_reference_method(p.reference_method, alpha_tilde)), description_(reference_description(p, alpha_tilde)),
      ds_(prob), newton_params_(p) {
  const MethodInfo* m = find_method("cholmod");
  if (!m || !m->available) throw Error("reference: the direct solver 'cholmod' is not available");
  const bool region = p.reference_globalization == "trust_region";
  if (!region && p.reference_trust_region_subproblem != StepperSettings{}.reference_trust_region_subproblem)
    throw Error("reference.trust_region_subproblem=" + p.reference_trust_region_subproblem +
                " needs reference.globalization=trust_region");
  if (region && p.reference_trust_region_subproblem == "more_sorensen" && p.reference_linear != "cholmod")
    throw Error("reference.trust_region_subproblem=more_sorensen factorises K + sigma K_c by CHOLMOD: it needs "
                "reference.linear=cholmod (with '" + p.reference_linear + "' use steihaug, preconditioned by it)");
  if (method_ == "xpbd" && region)
    throw Error("reference.globalization=trust_region needs reference.method=newton (XPBD's fixed point has no energy to "
                "globalise)");
  if (method_ == "xpbd") {
    direct_ = make_linear_solver("cholmod", p);
    return;
  }
  Params& q = newton_params_;
  q.step = "newton";  // GlobalStep assembles the energy Hessian
  q.form = "primal";
  q.geometric_stiffness = "full";
  q.primal_residual = "keep";
  q.cholmod.refactor = "always";
  q.linear.forcing = "fixed";
  q.linear.stop_norm = "primal";  // CHOLMOD's one solve, no refinement rounds; an iterative one stops on K's residual
  if (q.reference_linear != "cholmod") {  // tightened with ‖∇E‖ down to 1e-12 (harness/sim/forcing.hpp)
    q.linear.forcing = "eisenstat_walker";
    q.linear.tol = 1e-12;
    forcing_.emplace(q.linear);
  }
  newton_.emplace(prob_, ds_, q.reference_linear, q, alpha_tilde_);
  NewtonSettings s = NewtonSettings::from(q);  // the trust region's CG limit and direct solver
  s.stop = StopCriterion{};
  s.stop.rtol = settings.target_relative;
  s.stop.atol = 0;
  s.stop.max_iterations = settings.max_iterations;
  s.projection = parse_projection_strategy(projection);
  s.exact_below = StepperSettings{}.exact_hessian_below;
  s.line_search = LineSearchKind::robust_armijo;
  s.globalization = parse_globalization(p.reference_globalization, "reference.globalization");
  s.subproblem = parse_trust_region_subproblem(p.reference_trust_region_subproblem, "reference.trust_region_subproblem");
  loop_.emplace(prob_, ds_, *newton_, alpha_tilde_, h_, s);
  certificate_.emplace(prob_, ds_, *newton_, alpha_tilde_, h_);
}

Certificate ReferenceSolver::certify(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  if (!certificate_) throw Error("reference: only a newton reference has a certificate (reference.method = " + method_ + ")");
  return certificate_->certify(x, x_pred);
}

ReferenceSolution ReferenceSolver::solve(const Eigen::Matrix3Xd& x_pred) {
  ReferenceSolution out = method_ == "newton" ? solve_newton(x_pred) : solve_xpbd(x_pred);
  out.error_scale = position_error_scale(prob_, out.x, x_pred);
  if (method_ == "xpbd") out.certificate_note = "an XPBD fixed point, not the minimiser of E: no certificate";
  if (method_ == "xpbd" && (alpha_tilde_.array() > 0).all()) {
    ConstraintState s0, s;
    evaluate_constraints(prob_, x_pred, s0);
    evaluate_constraints(prob_, out.x, s);
    const double g0 = energy_gradient_norm(prob_, ds_, s0, x_pred, x_pred, alpha_tilde_, h_);
    const double g = energy_gradient_norm(prob_, ds_, s, out.x, x_pred, alpha_tilde_, h_);
    out.relative_energy_gradient = g0 > 0 ? g / g0 : g;
  }
  return out;
}

// The reference is the iterate with the smallest ‖∇E‖; its certificate reads the step that led to it.
ReferenceSolution ReferenceSolver::solve_newton(const Eigen::Matrix3Xd& x_pred) {
  ReferenceSolution out;
  out.x = x_pred;
  double best = INFINITY, last_step = 0, best_step = 0;
  Eigen::Matrix3Xd previous;
  NewtonHooks hooks;
  hooks.on_iterate = [&](const NewtonIterate& v) {
    last_step = v.iteration > 0 ? mass_norm_distance(prob_, v.x, previous) : 0;
    previous = v.x;
    if (!(v.gradient < best)) return;
    best = v.gradient;
    best_step = last_step;
    out.x = v.x;
    out.dual_residual = (v.state.C + alpha_tilde_.cwiseProduct(v.lambda)).norm();
    out.relative_energy_gradient = v.gradient0 > 0 ? v.gradient / v.gradient0 : 0;
  };
  if (forcing_) hooks.tolerance = [this](int it, double gradient) { return forcing_->next(it, gradient); };
  Eigen::Matrix3Xd x;
  const NewtonOutcome o = loop_->minimise(x, x_pred, hooks);
  out.iterations = o.iterations;
  out.status = o.reason;
  if (!out.x.allFinite()) {
    out.certificate_note = "the reference is not finite";
    return out;
  }
  const Certificate c = certificate_->certify(out.x, x_pred);
  const double scale = position_error_scale(prob_, out.x, x_pred);
  out.energy_gradient = c.gradient;
  out.gradient_floor = c.floor;
  out.contraction = c.contraction;
  out.error_estimate = scale > 0 ? c.error_bound / scale : c.error_bound;
  out.certified = c.positive_definite && std::isfinite(out.error_estimate);
  out.certificate_note = c.note;
  return out;
}

ReferenceSolution ReferenceSolver::solve_xpbd(const Eigen::Matrix3Xd& x_pred) {
  const Eigen::VectorXd& alpha_tilde = alpha_tilde_;
  const int m = prob_.num_constraints();
  Eigen::Matrix3Xd x = x_pred, dx;
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(m), b(m), dlambda;
  ConstraintState state;
  ReferenceSolution out;
  out.x = x_pred;
  double r0 = 0, best = INFINITY, best_at_window_start = INFINITY;
  int since_gain = 0;
  for (int it = 0;; ++it) {
    evaluate_constraints(prob_, x, state);
    b = -(state.C + alpha_tilde.cwiseProduct(lambda));
    const double dual = b.norm();
    if (it == 0) r0 = dual;
    if (!std::isfinite(dual) || !x.allFinite()) {
      out.status = StopReason::not_finite;
      break;
    }
    if (dual < best) {
      best = dual;
      out.x = x;
      out.dual_residual = dual;
      out.relative_dual_residual = r0 > 0 ? dual / r0 : 0;
    }
    if (dual <= target_relative * r0 || dual == 0) {
      out.status = StopReason::converged;
      break;
    }
    // Stagnation: the best value gained less than 1% over the last window of iterations.
    if (best < 0.99 * best_at_window_start) {
      best_at_window_start = best;
      since_gain = 0;
    } else if (++since_gain >= stagnation_window) {
      out.status = StopReason::stagnated;
      break;
    }
    if (it >= max_iterations) {
      out.status = StopReason::max_iterations;
      break;
    }
    ds_.fill(state, alpha_tilde);
    direct_->setup(ds_.A(), first_setup_ ? SetupKind::Structure : SetupKind::Values, SetupContext{0, 0, it});
    first_setup_ = false;
    const LinearStats st = direct_->solve(b, dlambda);
    ++out.iterations;
    if (st.status == LinearStatus::breakdown || !dlambda.allFinite()) {
      out.status = StopReason::solver_failed;
      break;
    }
    lambda += dlambda;
    ds_.apply_minv_gradT(state, dlambda, dx);
    x += dx;
    project_onto_planes(prob_, x);
  }
  return out;
}

double mass_norm_distance(const Problem& prob, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  const Eigen::VectorXd& w = prob.particles.w;
  return std::sqrt(
      deterministic_sum(a.cols(), [&](long p) { return w[p] > 0 ? (a.col(p) - b.col(p)).squaredNorm() / w[p] : 0.0; }));
}

double position_error_scale(const Problem& prob, const Eigen::Matrix3Xd& x_ref, const Eigen::Matrix3Xd& x_pred) {
  const Eigen::VectorXd& w = prob.particles.w;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  double mass = 0;
  for (long p = 0; p < x_pred.cols(); ++p)
    if (w[p] > 0) {
      lo = lo.cwiseMin(x_pred.col(p));
      hi = hi.cwiseMax(x_pred.col(p));
      mass += 1 / w[p];
    }
  const double body = mass > 0 ? std::sqrt(std::numeric_limits<double>::epsilon()) * (hi - lo).norm() * std::sqrt(mass) : 0;
  return std::max(mass_norm_distance(prob, x_ref, x_pred), body);
}

}  // namespace xb
