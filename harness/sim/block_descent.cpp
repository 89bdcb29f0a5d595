#include "block_descent.hpp"

#include "newton.hpp"
#include "residual_energy.hpp"

#include "../../solvers/timer.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

BlockDescentLoop::BlockDescentLoop(const Problem& prob, const DualSystem& ds, const Params& p, const std::string& method,
                                   const Eigen::VectorXd& alpha_tilde, double h)
    : prob_(prob), ds_(ds), alpha_tilde_(alpha_tilde), h_(h), stop_(NewtonSettings::from(p).stop), init_(p.block_descent.vbd.init),
      all_compliant_((alpha_tilde.array() > 0).all()), bounds_(prob) {
  if (method == "vbd")
    vbd_.emplace(prob, ds, p.block_descent.vbd, alpha_tilde, h);
  else
    avbd_.emplace(prob, ds, p.block_descent.avbd, alpha_tilde);
}

void BlockDescentLoop::evaluate(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, bool at_start) {
  evaluate_constraints(prob_, x, state_, newton_rest_epsilon);
  if (avbd_ && !at_start) {
    avbd_->multipliers(state_.C, lambda_);
  } else {  // compliant: −C/α̃; rigid: 0 (the scale at x̃, as every method's relative Newton residual)
    lambda_.resize(state_.C.size());
    for (long j = 0; j < lambda_.size(); ++j) lambda_[j] = alpha_tilde_[j] > 0 ? -state_.C[j] / alpha_tilde_[j] : 0.0;
  }
  primal_residual_vector(prob_, ds_, state_, x, x_pred, lambda_, g_);
  bounds_.active_set(x, g_, active_);
  Eigen::Matrix3Xd free = g_;
  PlaneBounds::free_gradient(active_, free);
  below_plane(x, free);
  primal_ = std::sqrt(particle_dot(prob_, free, free));
  dual_ = (state_.C + alpha_tilde_.cwiseProduct(lambda_)).norm();  // ‖C‖ of the rigid constraints
  measure_ = all_compliant_ ? primal_ / (h_ * h_) : std::hypot(primal_, dual_);
}

// Newton's iterates never cross the ground; these may. A particle below it is not at an optimum of
// the bound-constrained problem: its y entry is the natural residual m(y − max(y₀, y − g_y/m)), which
// is m(y − y₀) where g_y ≥ 0 (Newton's active set would zero it) and g_y where the step leaves the plane.
void BlockDescentLoop::below_plane(const Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& free) const {
  if (bounds_.empty()) return;
  const Eigen::VectorXd& w = prob_.particles.w;
  const double y0 = bounds_.height();
  for (int p = 0; p < static_cast<int>(x.cols()); ++p)
    if (w[p] > 0 && x(1, p) < y0) free(1, p) = (x(1, p) - std::max(y0, x(1, p) - g_(1, p) * w[p])) / w[p];
}

void BlockDescentLoop::start(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const Eigen::Matrix3Xd& v_t) {
  const Eigen::VectorXd& w = prob_.particles.w;
  const Eigen::Vector3d& a_ext = prob_.gravity;
  const double a2 = a_ext.squaredNorm();
  for (int i = 0; i < prob_.particles.size(); ++i) {
    if (!(w[i] > 0)) {
      x.col(i) = x_pred.col(i);
      continue;
    }
    double share = 1;  // of h² a_ext: inertia_acceleration
    if (init_ == "previous") {
      x.col(i) = x_t_.col(i);
      continue;
    }
    if (init_ == "inertia") share = 0;
    // adaptive: the last step's acceleration along a_ext, in [0, 1]; none known yet: 1 (x̃)
    if (init_ == "adaptive" && a2 > 0 && have_v_prev_)
      share = std::clamp((v_t.col(i) - v_prev_.col(i)).dot(a_ext) / (h_ * a2), 0.0, 1.0);
    x.col(i) = x_t_.col(i) + h_ * v_t.col(i) + share * h_ * h_ * a_ext;
  }
  // On the ground's bounds, as Newton's start: x⁽⁰⁾ = x̃'s projection under inertia_acceleration, so
  // that the measure starts where Newton's does (below the plane it reads only the inertia's share).
  bounds_.project(x);
}

NewtonOutcome BlockDescentLoop::minimise(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_t, const Eigen::Matrix3Xd& x_pred,
                                         const Eigen::Matrix3Xd& v_t, const BlockDescentHooks& hooks) {
  NewtonOutcome out;
  x_t_ = x_t;
  // The scale: the measure at x̃ on the bounds, as Newton's iteration 0.
  Eigen::Matrix3Xd x0 = x_pred;
  bounds_.project(x0);
  evaluate(x0, x_pred, true);
  if (avbd_) avbd_->begin_substep(x_t_);
  out.gradient0 = measure_;
  const double primal0 = primal_, dual0 = dual_;
  start(x, x_pred, v_t);
  v_prev_ = v_t;
  have_v_prev_ = true;
  if (vbd_) vbd_->begin_substep(x_t_);
  double sweep_time = 0;
  for (int it = 0;; ++it) {
    evaluate(x, x_pred, false);
    const double energy = incremental_energy(prob_, state_, x, x_pred, h_);
    out.gradient = measure_;
    out.floor = all_compliant_ ? gradient_rounding_floor(prob_, ds_, state_, x, alpha_tilde_) / (h_ * h_) : 0.0;
    out.iterations = it;
    if (hooks.on_iterate)
      hooks.on_iterate({it, x, state_, lambda_, measure_, out.gradient0, primal0, dual0, primal_, dual_, out.floor, energy,
                        static_cast<int>(active_.size()), sweep_time});
    const double gn = measure_;
    out.reason = stop_.test(it, gn, out.gradient0, out.floor, std::isfinite(energy) && x.allFinite());
    if (out.reason == StopReason::running && hooks.proceed && !hooks.proceed()) out.reason = StopReason::interrupted;
    if (out.reason != StopReason::running) return out;
    Timer clock;
    if (avbd_) {
      if (it > 0) avbd_->update_duals(x, state_.C);
      avbd_->sweep(x, x_pred);
    } else {
      vbd_->iterate(x, x_pred);
    }
    sweep_time = clock.seconds();
  }
}

std::map<std::string, double> BlockDescentLoop::statistics() const {
  return vbd_ ? vbd_->statistics() : avbd_->statistics();
}

}  // namespace xb
