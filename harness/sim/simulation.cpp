#include "simulation.hpp"
#include "simulation_impl.hpp"

#include "newton.hpp"
#include "residual_energy.hpp"

#include "../../core/error.hpp"
#include "../../core/process_memory.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <new>

namespace xb {

namespace detail {

Simulation::Simulation(const Problem& prob, const Params& p, const std::string& method, const RunOptions& opt)
    : p_(p), method_(method), opt_(opt), prob_(prob), ds_(prob_), h_(p.dt / p.substeps),
      alpha_tilde_(scaled_compliance(prob_, h_)), newton_(p.step == "newton"), m_(p.linear), stability_(prob_, p) {
  check_combination(method);
  m_.criterion.rtol = p.rtol;
  m_.criterion.atol = p.atol;
  m_.criterion.max_iterations = p.max_iterations;
  if (!newton_) m_.projection = parse_projection(p.hessian_projection, "xpbd.hessian_projection");
  if (opt.reference) {
    if (!opt.reference_file.empty()) truth_.store.emplace(opt.reference_file, p, prob_, alpha_tilde_);
    res_.reference_file = opt.reference_file;
    res_.reference_method = truth_.store ? truth_.store->method() : reference_description(p, alpha_tilde_);
  }
  if (find_method(method)->block_descent) {
    m_.block.emplace(prob_, ds_, p, method, alpha_tilde_, h_);
    res_.form_used = "none";
  } else if (find_method(method)->local) {
    m_.local.emplace(prob_, ds_, p.xpbd, local_kind(method));
    res_.form_used = "none";
  } else {
    m_.global.emplace(prob_, ds_, method, p, alpha_tilde_);
    res_.form_used = m_.global->form();
    m_.active = &m_.global->solver();
    if (newton_) m_.newton.emplace(prob_, ds_, *m_.global, alpha_tilde_, h_, NewtonSettings::from(p));
  }
  substep_.lambda.resize(prob_.num_constraints());
}

// The outer-method keys a method cannot take: one message naming the key (docs/newton.md).
void Simulation::check_combination(const std::string& method) const {
  check_block_descent_keys(p_.block_descent, method);
  if (find_method(method)->block_descent) {
    auto refuse = [&](const std::string& what) {
      throw Error("solver '" + method + "' is block descent on E with its own outer loop: " + what + " is XPBD's or Newton's");
    };
    if (p_.step != "fixed") refuse("step=" + p_.step);
    if (p_.geometric_stiffness != "none") refuse("xpbd.geometric_stiffness=" + p_.geometric_stiffness);
    if (p_.primal_residual != "zero") refuse("xpbd.primal_residual=" + p_.primal_residual);
    if (p_.hessian_projection != "clamp") refuse("xpbd.hessian_projection=" + p_.hessian_projection + " (vbd.projection is VBD's)");
    if (p_.residual_metric != "true") refuse("residual_metric=" + p_.residual_metric + " (it stops on |grad E|)");
    if (p_.globalization != "line_search") refuse("xpbd.globalization=" + p_.globalization);
    if (p_.trust_region_subproblem != "steihaug") refuse("xpbd.trust_region_subproblem=" + p_.trust_region_subproblem);
    return;
  }
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
    where_.first_frame = start;
    for (int frame = start; frame < start + p_.frames && !stop_; ++frame) {
      for (int sub = 0; sub < p_.substeps && !stop_; ++sub) substep(frame, sub);
      if (!stop_ && opt_.on_frame) opt_.on_frame(frame, prob_.particles.x);
      if (!stop_ && opt_.on_state) opt_.on_state(SimState{frame + 1, prob_.particles.x, prob_.particles.v});
    }
  } catch (const OutOfMemory& e) {
    fail("out_of_memory", std::string(e.what()) + " (in " + where_.phase + " at frame " + std::to_string(where_.frame) +
                              ", iteration " + std::to_string(where_.iteration) + ")");
  } catch (const std::bad_alloc&) {
    fail("out_of_memory", "out of memory in " + where_.phase + " at frame " + std::to_string(where_.frame) + ", iteration " +
                              std::to_string(where_.iteration));
  } catch (const std::exception& e) {
    fail("error", e.what());
  }
  finish();
  return std::move(res_);
}

// Checked every outer iteration and every substep, so that no count of either escapes it.
bool Simulation::over_budget(double excluded) {
  if (opt_.memory_limit > 0) {
    const long long rss = resident_bytes();
    if (rss > opt_.memory_limit) {
      fail("out_of_memory", "resident set " + gigabytes(static_cast<double>(rss)) + " over the memory limit of " +
                                gigabytes(opt_.memory_limit) + " at frame " + std::to_string(where_.frame) + ", iteration " +
                                std::to_string(where_.iteration));
      return true;
    }
  }
  return over_time(excluded);
}

bool Simulation::over_time(double excluded) {
  if (opt_.time_budget <= 0 || clock_.run.seconds() - res_.reference_time - excluded <= opt_.time_budget) return false;
  char budget[32];
  std::snprintf(budget, sizeof budget, "%g", opt_.time_budget);
  fail("over_budget", std::string("time budget of ") + budget + " s exceeded");
  return true;
}

ReferenceSolution Simulation::solve_reference(int frame, int sub) {
  if (truth_.store)
    if (std::optional<ReferenceSolution> r = truth_.store->find(frame, sub, substep_.x_pred)) {
      res_.log.reference_source.push_back("read");
      return std::move(*r);
    }
  Timer clock;
  where_.phase = "the reference";
  if (!truth_.solver) truth_.solver.emplace(prob_, p_, alpha_tilde_);
  ReferenceSolution r = truth_.solver->solve(substep_.x_pred);
  if (truth_.store)
    res_.log.reference_source.push_back(truth_.store->store(frame, sub, substep_.x_pred, r, clock.seconds()) ? "stored" : "computed");
  return r;
}

void Simulation::substep(int frame, int sub) {
  if (over_time(0)) return;
  Particles& P = prob_.particles;
  clock_.sub.reset();
  substep_.x_old = P.x;
  substep_.v_old = P.v;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) P.v.col(i) += h_ * prob_.gravity;
  substep_.x_pred = P.x + h_ * P.v;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] == 0) substep_.x_pred.col(i) = P.x.col(i);  // pins stay
  P.x = substep_.x_pred;
  substep_.lambda.setZero();
  clock_.excluded = 0;
  if (opt_.reference) {
    Timer ref_clock;
    ReferenceSolution rs = solve_reference(frame, sub);
    res_.log.reference_time.push_back(ref_clock.seconds());
    log_reference(rs);
    truth_.x = std::move(rs.x);
    truth_.scale = rs.error_scale;
    clock_.excluded += res_.log.reference_time.back();
  }
  ++res_.substeps_total;
  if (newton_) {
    newton_substep(frame, sub);
  } else if (m_.block) {
    block_descent_substep(frame, sub);
  } else {
    xpbd_substep(frame, sub);
  }
  res_.reference_time += clock_.excluded;
  if (stop_) return;
  if (!m_.block) project_onto_planes(prob_, P.x);  // block descent has the ground in its own energy
  P.v = (P.x - substep_.x_old) / h_;
  if (std::string st, msg; !stability_.check(P, frame, sub, st, msg)) fail(st, msg);
}

// XPBD's outer loop (Algorithm 4), every method but step = newton: the stop criterion on the
// dual residual (divergence) and on the stop metric (convergence).
void Simulation::xpbd_substep(int frame, int sub) {
  Particles& P = prob_.particles;
  StopReason reason = StopReason::running;
  LastStep last;
  for (int it = 0;; ++it) {
    where_.frame = frame;
    where_.iteration = it;
    where_.phase = "the constraint evaluation";
    const Residuals r = log_state(frame, sub, it, last);
    if (opt_.on_iteration)
      opt_.on_iteration({frame, where_.first_frame, p_.frames, sub, p_.substeps, it, p_.max_iterations, substep_.r0 > 0 ? r.dual / substep_.r0 : 0});
    const std::string where = " at frame " + std::to_string(frame) + ", iteration " + std::to_string(it);
    if (!std::isfinite(r.dual) || !std::isfinite(r.stop) || !P.x.allFinite()) {
      fail("nan", "non-finite positions or dual residual" + where);
      break;
    }
    if (m_.criterion.diverged(r.dual, substep_.r0)) {
      fail("diverged", "dual residual grew by more than 1e8 over its first value" + where);
      break;
    }
    if (m_.criterion.converged(r.stop, substep_.r0)) reason = StopReason::converged;
    else if (it >= p_.max_iterations) reason = StopReason::max_iterations;
    if (reason != StopReason::running || over_budget(clock_.excluded)) break;
    Timer step_clock;
    if (step(frame, sub, it, r.dual, last) != StepEnd::ok) break;
    project_onto_planes(prob_, P.x);
    last.time = step_clock.seconds();
    ++res_.outer_iterations;
  }
  if (!stop_) end_substep(reason);
}

void Simulation::log_reference(const ReferenceSolution& rs) {
  IterationLog& L = res_.log;
  L.reference_relative_dual_residual.push_back(rs.relative_dual_residual);
  if (rs.relative_energy_gradient >= 0) L.reference_relative_energy_gradient.push_back(rs.relative_energy_gradient);
  L.reference_iterations.push_back(rs.iterations);
  L.reference_status.push_back(stop_reason_name(rs.status));
  L.reference_success.push_back(stop_reason_success(rs.status) ? 1 : 0);
  L.reference_energy_gradient.push_back(rs.energy_gradient);
  L.reference_gradient_floor.push_back(rs.gradient_floor);
  L.reference_error_scale.push_back(rs.error_scale);
  L.reference_error_estimate.push_back(rs.error_estimate);
  L.reference_contraction.push_back(rs.contraction);
  L.reference_certified.push_back(rs.certified ? 1 : 0);
  L.reference_certified_threshold.push_back(rs.certified_threshold());
  L.reference_certificate_note.push_back(rs.certificate_note);
}

void Simulation::end_substep(StopReason reason) {
  res_.log.substep_status.push_back(stop_reason_name(reason));
  res_.log.substep_success.push_back(stop_reason_success(reason) ? 1 : 0);
  switch (reason) {
    case StopReason::converged: ++res_.substeps_converged; break;
    case StopReason::rounding_floor: ++ends_.rounding_floor; break;
    case StopReason::line_search_at_floor: ++ends_.search_at_floor; [[fallthrough]];
    case StopReason::line_search_failed: ++ends_.search_failures; break;
    case StopReason::trust_region_at_floor: ++ends_.region_at_floor; [[fallthrough]];
    case StopReason::trust_region_failed: ++ends_.region_failures; break;
    default: ++ends_.max_iterations;
  }
}

void Simulation::finish() {
  if (res_.status == "ok" && ends_.search_failures > 0) {
    res_.status = "line_search_failed";
    res_.message = std::to_string(ends_.search_failures) + " of " + std::to_string(res_.substeps_total) +
                   " substeps ended on a failed line search on E (no step of 1, 1/2, ..., 1e-9 passed it, with |grad E| "
                   "above its rounding floor" +
                   (ends_.search_at_floor > 0 ? "; " + std::to_string(ends_.search_at_floor) + " of them within 1e2 of it: line_search_at_floor"
                                         : std::string()) + ")";
  } else if (res_.status == "ok" && ends_.region_failures > 0) {
    res_.status = "trust_region_failed";
    res_.message = std::to_string(ends_.region_failures) + " of " + std::to_string(res_.substeps_total) +
                   " substeps ended with the trust region collapsed (every step rejected until its radius fell below "
                   "1e-12 of its first, with |grad E| above its rounding floor" +
                   (ends_.region_at_floor > 0 ? "; " + std::to_string(ends_.region_at_floor) + " of them within 1e2 of it: trust_region_at_floor"
                                              : std::string()) + ")";
  } else if (res_.status == "ok" && ends_.max_iterations > 0) {
    res_.status = "max_iterations";
    res_.message = std::to_string(ends_.max_iterations) + " of " + std::to_string(res_.substeps_total) +
                   " substeps stopped at max_iterations";
  }
  reference_verdict();
  res_.wall_time = clock_.run.seconds() - res_.reference_time;
  if (m_.active) {
    res_.stats = m_.active->statistics();
    res_.arrays = m_.active->array_statistics();
  }
  if (m_.local)
    for (const auto& [key, value] : m_.local->statistics()) res_.stats[key] = value;
  if (m_.block)
    for (const auto& [key, value] : m_.block->statistics()) res_.stats[key] = value;
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
  if (m_.global && m_.global->primal()) {
    res_.stats["primal_rows"] = m_.global->primal()->system().rows();
    res_.stats["primal_nonzeros"] = static_cast<double>(m_.global->primal()->system().K().nonZeros());
  }
  res_.stats["particles"] = prob_.particles.size();
  if (newton_) res_.stats["line_search_failures"] = ends_.search_failures;
  if (newton_ || m_.block) res_.stats["substeps_rounding_floor"] = ends_.rounding_floor;
  // The process's largest resident set so far (its earlier runs included), and the limit it ran under.
  res_.stats["peak_memory"] = static_cast<double>(peak_resident_bytes());
  if (opt_.memory_limit > 0) res_.stats["memory_limit"] = opt_.memory_limit;
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
    r.status = "out_of_memory";
    r.message = "out of memory in the set-up of the run (" + method + ": the problem's copy, A's pattern, the solver)";
    return r;
  }
}

}  // namespace xb
