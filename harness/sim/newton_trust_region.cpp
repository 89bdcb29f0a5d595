// The trust region of Newton on E (harness/sim/trust_region.hpp has the rules): NewtonLoop's step
// when xpbd.globalization = trust_region (or reference.globalization).
#include "negative_curvature.hpp"
#include "newton.hpp"
#include "newton_loop.hpp"
#include "residual_energy.hpp"

#include "../../core/error.hpp"
#include "../../solvers/direct/more_sorensen.hpp"
#include "../../solvers/kernels.hpp"
#include "../../solvers/krylov/steihaug.hpp"

#include <cmath>
#include <optional>

namespace xb {

namespace {
// Element modes tried per iteration for directions of negative curvature (the most negative first).
constexpr int max_mode_candidates = 4096;
// One solve of the subproblem: the step and what the records say of it.
struct SubproblemStep {
  const Vector* p = nullptr;
  double model = 0, norm = 0, shift = 0;
  bool boundary = false, negative_curvature = false;
};

// The element modes u against the CG step p: the better (by the model) of p, p carried on along
// v to the boundary (where p is inside) and v alone to the boundary, v = P⁻¹w, w = K_c u (P's own
// matrix stood in for by the clamped K it was built on; w = u where P = I), so that ‖v‖²_P = vᵀw
// and pᵀPv = pᵀw are known without P. CG from −g never sees a negative curvature that g has no
// component along (a saddle's axis); the modes do.
void improve_along_modes(const SparseMatrix& K, const SparseMatrix* Kc, const Preconditioner& P, const Vector& g,
                         const Vector& u, double radius, SteihaugResult& r, Vector& w, Vector& v, Vector& Kv) {
  if (P && Kc) {
    spmv(*Kc, u, w);
    P(w, v);
  } else {
    w = u;
    v = u;
  }
  const double vKv = spmv_dot(K, v, Kv), vw = dot(v, w), gv = dot(g, v);
  if (!(vKv < 0) || !(vw > 0)) return;
  // v alone: τ = Δ/‖v‖_P, downhill.
  const double tau0 = (gv > 0 ? -1 : 1) * radius / std::sqrt(vw);
  double best = tau0 * gv + 0.5 * tau0 * tau0 * vKv, along = tau0;
  bool from_p = false;
  if (r.exit != SteihaugExit::boundary && r.exit != SteihaugExit::negative_curvature) {
    const double slope = gv + dot(r.Kp, v);  // (g + Kp)ᵀv
    const double sign = slope > 0 ? -1 : 1;
    const double tau = sign * step_to_boundary(r.norm * r.norm, sign * dot(r.p, w), vw, radius);
    const double model = r.model + tau * slope + 0.5 * tau * tau * vKv;
    if (model < best) best = model, along = tau, from_p = true;
  }
  if (!(best < r.model)) return;
  if (!from_p) {
    r.p.setZero();
    r.Kp.setZero();
  }
  axpy(along, v, r.p);
  axpy(along, Kv, r.Kp);
  r.model = best;
  r.norm = radius;
  r.exit = SteihaugExit::negative_curvature;
}
}  // namespace


struct NewtonLoop::TrustRegionState {
  TrustRegionState(const Problem& prob, const NewtonSettings& s) : exact(constraint_graph(prob)) {
    if (s.subproblem == TrustRegionSubproblem::more_sorensen) {
      clamped.emplace(constraint_graph(prob));
      if (!s.make_direct) throw Error("xpbd.trust_region_subproblem=more_sorensen: no direct solver to factorise K + sigma K_c");
      ms.emplace(s.make_direct());
    }
    const auto& free = exact.free_particles();
    mass.resize(3 * static_cast<long>(free.size()));
    for (size_t i = 0; i < free.size(); ++i) mass.segment<3>(3 * i).setConstant(1.0 / prob.particles.w[free[i]]);
  }
  PrimalSystem exact;                    // K = h²∇²E, unprojected
  std::optional<PrimalSystem> clamped;   // more_sorensen: K_c, every element clamped (the region's norm)
  std::optional<MoreSorensen> ms;        // more_sorensen
  Vector mass;                           // per free dof (the modes' scale)
  Vector g, p, w, v, Kv;            // per dof
  std::vector<int> held;            // K's rows held (contact)
  double radius = 0, first_radius = 0;
  // This iteration's models: the preconditioner (steihaug), the matrix it was built on, the modes.
  Preconditioner P;
  const SparseMatrix* Kc = nullptr;
  NegativeCurvature nc;
  std::optional<SteihaugResult> cg;
  std::optional<MoreSorensenResult> msr;

  // The subproblem at the current radius; false with `message` where More-Sorensen failed.
  bool solve(const NewtonSettings& s, double tol, SubproblemStep& sp, StepRecord& rec, std::string& message) {
    const SparseMatrix& K = exact.K();
    if (s.subproblem == TrustRegionSubproblem::steihaug) {
      cg = steihaug_toint(K, g, radius, P, tol, s.linear_max_iterations);
      rec.linear.iterations += cg->iterations;
      if (nc.combined.size()) improve_along_modes(K, Kc, P, g, nc.combined, radius, *cg, w, v, Kv);
      const bool nc_exit = cg->exit == SteihaugExit::negative_curvature;
      sp = {&cg->p, cg->model, cg->norm, 0, nc_exit || cg->exit == SteihaugExit::boundary, nc_exit};
      return true;
    }
    msr = ms->solve(K, RegionNorm{nullptr, &clamped->K()}, g, radius, nc.best.size() ? &nc.best : nullptr);
    rec.linear.iterations += msr->factorisations;
    if (!msr->ok) {
      message = "More-Sorensen: " + msr->message;
      return false;
    }
    sp = {&msr->p, msr->model, msr->norm, msr->sigma, msr->boundary, msr->hard_case};
    return true;
  }
};

void NewtonLoop::TrustRegionDelete::operator()(TrustRegionState* t) const { delete t; }

void NewtonLoop::make_trust_region() { tr_.reset(new TrustRegionState(prob_, s_)); }

void NewtonLoop::begin_trust_region() { tr_->radius = tr_->first_radius = 0; }

bool NewtonLoop::trust_region_models(int it, const Eigen::Matrix3Xd& x, StepRecord& rec, const NewtonHooks& hooks,
                                     NewtonOutcome& out) {
  TrustRegionState& tr = *tr_;
  ElementHessians& eh = *step_.elements();
  const bool steihaug = s_.subproblem == TrustRegionSubproblem::steihaug;
  const auto& free = tr.exact.free_particles();
  const long nb = static_cast<long>(free.size());
  // Contact: the active bounds' y held (K's row 3i + 1 of free particle i). Not the line search's
  // ε-active set: holding it cost the region more steps on ball_drop and, with mgpbd, a collapse.
  tr.held.clear();
  if (!active_.empty()) {
    std::vector<int> block(prob_.particles.size(), -1);
    for (long i = 0; i < nb; ++i) block[free[i]] = static_cast<int>(i);
    for (int q : active_)
      if (block[q] >= 0) tr.held.push_back(3 * block[q] + 1);
  }
  ElementProjection proj{Projection::clamp, 0};
  const GlobalStepInput in{state_, lambda_, x, g_, b_, proj.base, &proj, &active_, true};
  tr.P = nullptr;
  tr.Kc = nullptr;
  if (steihaug) {  // the run's linear method on the clamped K: Steihaug–Toint's preconditioner
    if (hooks.phase) hooks.phase("the setup of the trust region's preconditioner");
    rec.hessians += step_.prepare(in);
    step_.setup(in, first_setup_ ? SetupKind::Structure : SetupKind::Values, SetupContext{hooks.frame, hooks.substep, it});
    first_setup_ = false;
    rec.fill += step_.primal_fill_time();
    rec.action = step_.solver().last_setup_action();
    tr.P = step_.solver().preconditioner();
    tr.Kc = &step_.primal()->system().K();
    if (!tr.P && step_.solver().name() != "cg") {
      out.reason = StopReason::solver_failed;
      out.message = "the setup of " + step_.solver().name() + " on the clamped Hessian failed (no preconditioner)";
      return false;
    }
    if (tr.P && !tr.held.empty())  // keep the held rows out of CG's directions
      tr.P = [inner = tr.P, &held = tr.held](const Vector& r, Vector& z) {
        inner(r, z);
        for (int d : held) z[d] = 0;
      };
  }
  if (tr.clamped) {  // more_sorensen: K_c, the region's norm
    rec.hessians += step_.prepare(in);
    tr.clamped->fill_energy_hessian(eh.blocks());
    tr.clamped->fix_dofs(tr.held);
  }
  if (hooks.phase) hooks.phase("the exact Hessian of the trust region's model");
  proj.base = Projection::none;
  rec.hessians += step_.prepare(in);
  tr.exact.fill_energy_hessian(eh.blocks());
  tr.exact.fix_dofs(tr.held);
  rec.exact = true;
  rec.indefinite = eh.indefinite_elements();
  tr.g.resize(3 * nb);
  for (long i = 0; i < nb; ++i) tr.g.segment<3>(3 * i) = g_.col(free[i]);
  for (int d : tr.held) tr.g[d] = 0;
  tr.nc = NegativeCurvature{};
  if (eh.indefinite_elements() > 0)
    tr.nc = negative_curvature(prob_, eh, x, alpha_tilde_, tr.exact, tr.exact.K(), tr.mass, tr.g, tr.held, max_mode_candidates);
  rec.curvature = tr.nc.smallest;
  if (tr.radius == 0) {  // the substep's first: the Cauchy point's length along z = P⁻¹g, in the region's norm
    if (tr.P)
      tr.P(tr.g, tr.w);
    else if (tr.clamped)
      tr.w = tr.g.cwiseQuotient(diagonal(tr.clamped->K()));  // Jacobi's z; its K_c-norm by one product
    else
      tr.w = tr.g;
    const double gz = std::max(0.0, dot(tr.g, tr.w)), zKz = spmv_dot(tr.exact.K(), tr.w, tr.v);
    const double zz = tr.clamped ? RegionNorm{nullptr, &tr.clamped->K()}.dot(tr.w, tr.w) : tr.P ? gz : dot(tr.w, tr.w);
    tr.radius = (zKz > 0 ? gz / zKz : 1.0) * std::sqrt(zz);
    tr.first_radius = tr.radius;
  }
  return true;
}

bool NewtonLoop::trust_region_saddle() const { return tr_->nc.smallest < 0; }

bool NewtonLoop::trust_region_step(int it, Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, StepRecord& rec,
                                   const NewtonHooks& hooks, NewtonOutcome& out) {
  (void)it;
  TrustRegionState& tr = *tr_;
  const auto& free = tr.exact.free_particles();
  const long nb = static_cast<long>(free.size());
  const double tol = hooks.tolerance ? rec.tolerance : step_.solver().tolerance();
  const double h2 = h_ * h_;
  if (hooks.phase) hooks.phase("the trust region's subproblem and trial");
  const double rounding = 2 * energy_rounding(prob_, state_, x, x_pred, h_, energy_);  // of E(x + p) − E(x)
  for (;;) {
    SubproblemStep sp;
    if (!tr.solve(s_, tol, sp, rec, out.message)) {
      out.reason = StopReason::solver_failed;
      return false;
    }
    ++rec.solves;
    // The trial x + p (onto the planes), its E and the decrease the model predicted.
    trial_.x = x;
    for (long i = 0; i < nb; ++i) trial_.x.col(free[i]) += sp.p->segment<3>(3 * i);
    bounds_.project(trial_.x);
    evaluate_at(trial_.x, trial_.state);
    ++rec.trials;
    const double e = incremental_energy(prob_, trial_.state, trial_.x, x_pred, h_);
    const double predicted = -sp.model / h2;
    double actual = energy_ - e;
    eliminate_multipliers(trial_.state, alpha_tilde_, trial_.lambda);
    primal_residual_vector(prob_, ds_, trial_.state, trial_.x, x_pred, trial_.lambda, trial_.g);
    if (std::abs(actual) <= rounding) {
      const Eigen::Matrix3Xd s = trial_.x - x;  // E's change below its rounding: the trapezoid rule
      actual = -0.5 * (particle_dot(prob_, g_, s) + particle_dot(prob_, trial_.g, s)) / h2;
    }
    const double rho = predicted > 0 && std::isfinite(e) ? actual / predicted : -INFINITY;
    const double next = RadiusRule::next(tr.radius, rho, sp.norm, sp.boundary);
    if (RadiusRule::accepted(rho)) {
      rec.radius = tr.radius;
      rec.ratio = rho;
      rec.boundary = sp.boundary;
      rec.negative_curvature = sp.negative_curvature;
      rec.shift = sp.shift;
      rec.actual = actual;
      rec.predicted = predicted;
      rec.length = 1;
      tr.radius = next;
      accept_trial(x, e);
      return true;
    }
    ++rec.rejected;
    tr.radius = next;
    if (!(tr.radius >= trust_region_min_radius * tr.first_radius)) {
      out.reason = StopCriterion::failed_region(out.gradient, out.floor);
      out.message = "the trust region's radius fell below 1e-12 of its first value with every step rejected";
      return false;
    }
  }
}

}  // namespace xb
