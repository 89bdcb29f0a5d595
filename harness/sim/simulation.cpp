#include "simulation.hpp"
#include "simulation_impl.hpp"

#include "newton.hpp"
#include "residual_energy.hpp"

#include "../../core/error.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <new>

namespace xb {

namespace detail {

Simulation::Simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt)
    : p_(p), method_(method), opt_(opt), prob_(prob), ds_(prob_), h_(p.dt / p.substeps),
      alpha_tilde_(scaled_compliance(prob_, h_)), newton_(p.step == "newton"), stability_(prob_, p),
      forcing_(p.linear) {
  check_combination(method);
  if (opt.reference) {
    Timer ref_clock;
    reference_.emplace(prob_, p, alpha_tilde_);
    res_.reference_method = reference_->description();
    res_.reference_time += ref_clock.seconds();
  }
  if (find_method(method)->local) {
    local_.emplace(prob_, ds_, p.xpbd, local_kind(method));
    res_.form_used = "none";
  } else {
    global_.emplace(prob_, ds_, method, p, alpha_tilde_);
    res_.form_used = global_->form();
    active_ = &global_->solver();
    if (newton_) newton_loop_.emplace(prob_, ds_, *global_, alpha_tilde_, h_, NewtonSettings::from(p));
  }
  lambda_.resize(prob_.num_constraints());
}

// The outer-method keys a method cannot take: one message naming the key (docs/newton.md).
void Simulation::check_combination(const std::string& method) const {
  const bool local = find_method(method)->local;
  auto refuse = [&](const std::string& what) {
    throw Error("solver '" + method + "' is a local XPBD sweep: " + what +
                " needs a global linear method (cholmod, mgpbd, jacobi-pcg, ...)");
  };
  if (local && newton_) refuse("step=newton (Newton's method on E)");
  if (local && p_.geometric_stiffness != "none") refuse("xpbd.geometric_stiffness=" + p_.geometric_stiffness);
  if (local && p_.primal_residual != "zero") refuse("xpbd.primal_residual=" + p_.primal_residual);
  if (newton_ && p_.primal_residual != "keep")
    throw Error("step=newton needs xpbd.primal_residual=keep (with g zeroed and lambda = -C/alpha~ the step's "
                "right-hand side is 0); --profile newton sets it");
  // Without the constraints' Hessians K is M + Jᵀα̃⁻¹J (or its diagonal part): Gauss–Newton on E, not
  // Newton: on bar_hang ‖∇E‖ is still 0.59 of its start after 100 iterations, where Newton takes 3.
  if (newton_ && p_.geometric_stiffness != "full")
    throw Error("step=newton needs xpbd.geometric_stiffness=full (with " + p_.geometric_stiffness +
                " its K lacks the constraints' Hessians: Gauss-Newton on E, not Newton); --profile newton sets it");
  if (p_.hessian_projection != "clamp" && p_.hessian_projection != "abs" && !newton_)
    throw Error("xpbd.hessian_projection=" + p_.hessian_projection +
                " needs step=newton (a strategy of Newton on E; XPBD's full geometric stiffness takes clamp or abs)");
  check_globalization(method);
  if (newton_)
    for (long j = 0; j < alpha_tilde_.size(); ++j)
      if (!(alpha_tilde_[j] > 0))
        throw Error("step=newton needs every constraint compliant (alpha~ > 0): E(x) has no term for constraint " +
                    std::to_string(j) + " of compliance 0 (use step=fixed)");
}

// The trust region's keys (harness/sim/trust_region.hpp) where they apply, and only there.
void Simulation::check_globalization(const std::string& method) const {
  const bool region = p_.globalization == "trust_region";
  if (region && !newton_)
    throw Error("xpbd.globalization=trust_region needs step=newton (a globalisation of Newton on E); --profile newton sets it");
  if (!region && p_.trust_region_subproblem != "steihaug")
    throw Error("xpbd.trust_region_subproblem=" + p_.trust_region_subproblem +
                " needs xpbd.globalization=trust_region (the line search solves no subproblem)");
  if (region && p_.trust_region_subproblem == "more_sorensen" && method != "cholmod")
    throw Error("xpbd.trust_region_subproblem=more_sorensen factorises K + sigma K_c by CHOLMOD: it needs --solver cholmod "
                "(with '" + method + "' use xpbd.trust_region_subproblem=steihaug, preconditioned by it)");
  if (region && p_.line_search != "robust_armijo")
    throw Error("xpbd.line_search=" + p_.line_search + " has no effect under xpbd.globalization=trust_region (the ratio of "
                "actual to predicted decrease judges each step)");
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
    ReferenceSolution rs = reference_->solve(x_pred_);
    x_ref_ = std::move(rs.x);
    ref_scale_ = mass_norm_distance(prob_, x_ref_, x_pred_);
    res_.log.reference_relative_dual_residual.push_back(rs.relative_dual_residual);
    if (rs.relative_energy_gradient >= 0) res_.log.reference_relative_energy_gradient.push_back(rs.relative_energy_gradient);
    res_.log.reference_iterations.push_back(rs.iterations);
    res_.log.reference_status.push_back(rs.status);
    res_.log.reference_time.push_back(ref_clock.seconds());
    excluded_ += res_.log.reference_time.back();
  }
  ++res_.substeps_total;
  if (newton_) {
    newton_substep(frame, sub);
  } else {
    xpbd_substep(frame, sub);
  }
  res_.reference_time += excluded_;
  if (stop_) return;
  project_onto_planes(prob_, P.x);
  P.v = (P.x - x_old_) / h_;
  if (std::string st, msg; !stability_.check(P, frame, sub, st, msg)) fail(st, msg);
}

// XPBD's outer loop (Algorithm 4), every method but step = newton.
void Simulation::xpbd_substep(int frame, int sub) {
  Particles& P = prob_.particles;
  bool converged = false;
  LastStep last;
  for (int it = 0;; ++it) {
    frame_ = frame;
    iteration_ = it;
    phase_ = "the constraint evaluation";
    const Residuals r = log_state(frame, sub, it, last);
    if (opt_.on_iteration)
      opt_.on_iteration({frame, first_frame_, p_.frames, sub, p_.substeps, it, p_.max_iterations, r0_ > 0 ? r.dual / r0_ : 0});
    const std::string where = " at frame " + std::to_string(frame) + ", iteration " + std::to_string(it);
    if (!std::isfinite(r.dual) || !std::isfinite(r.stop) || !P.x.allFinite()) {
      fail("nan", "non-finite positions or dual residual" + where);
      break;
    }
    if (r.dual > divergence_factor * r0_ && r.dual > p_.atol) {
      fail("diverged", "dual residual grew by more than 1e8 over its first value" + where);
      break;
    }
    if (r.stop <= p_.rtol * r0_ || r.stop <= p_.atol) {
      converged = true;
      break;
    }
    if (it >= p_.max_iterations) break;
    if (over_budget(excluded_)) break;
    Timer step_clock;
    if (step(frame, sub, it, r.dual, last) != StepEnd::ok) break;
    project_onto_planes(prob_, P.x);
    last.time = step_clock.seconds();
    ++res_.outer_iterations;
  }
  if (!stop_) end_substep(converged ? "converged" : "max_iterations");
}

void Simulation::end_substep(const std::string& status) {
  res_.log.substep_status.push_back(status);
  if (status == "converged") {
    ++res_.substeps_converged;
  } else if (status == "rounding_floor") {
    ++rounding_floor_;
  } else if (status == "line_search_failed") {
    ++search_failures_;
  } else if (status == "trust_region_failed") {
    ++region_failures_;
  } else {
    ++max_iteration_substeps_;
  }
}

void Simulation::finish() {
  if (res_.status == "ok" && search_failures_ > 0) {
    res_.status = "line_search_failed";
    res_.message = std::to_string(search_failures_) + " of " + std::to_string(res_.substeps_total) +
                   " substeps ended on a failed line search on E (no step of 1, 1/2, ..., 1e-9 passed it, with |grad E| "
                   "above its rounding floor)";
  } else if (res_.status == "ok" && region_failures_ > 0) {
    res_.status = "trust_region_failed";
    res_.message = std::to_string(region_failures_) + " of " + std::to_string(res_.substeps_total) +
                   " substeps ended with the trust region collapsed (every step rejected until its radius fell below "
                   "1e-12 of its first, with |grad E| above its rounding floor)";
  } else if (res_.status == "ok" && max_iteration_substeps_ > 0) {
    res_.status = "max_iterations";
    res_.message = std::to_string(max_iteration_substeps_) + " of " + std::to_string(res_.substeps_total) +
                   " substeps stopped at max_iterations";
  }
  reference_verdict();
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
  if (global_ && global_->primal()) {
    res_.stats["primal_rows"] = global_->primal()->system().rows();
    res_.stats["primal_nonzeros"] = static_cast<double>(global_->primal()->system().K().nonZeros());
  }
  if (newton_) {
    res_.stats["line_search_failures"] = search_failures_;
    res_.stats["substeps_rounding_floor"] = rounding_floor_;
  }
  res_.stats["particles"] = prob_.particles.size();
  res_.final_positions = prob_.particles.x;
}

}  // namespace detail

RunResult run_simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt) {
  const MethodInfo* info = find_method(method);
  if (!info) (void)make_linear_solver(method, p);  // throws with the valid names
  if (!info->available) throw Error("solver '" + method + "' is not available: " + info->reason);
  if (p.threads > 0) omp_set_num_threads(p.threads);
  try {
    return detail::Simulation(prob, p, method, opt).run();
  } catch (const std::bad_alloc&) {  // the run's copies of the problem and its systems
    RunResult r;
    r.status = "error";
    r.message = "out of memory in the set-up of the run (" + method + ": the problem's copy, A's pattern, the solver)";
    return r;
  }
}

}  // namespace xb
