#include "reference.hpp"

#include "../../core/error.hpp"

#include <cmath>

namespace xb {

std::string reference_method_description() {
  return "cholmod (global direct solve of A dlambda = -(C + alpha~ lambda)), omega = 1, from the substep's "
         "predicted state x~ with lambda = 0, recomputed every substep from the run's own state; stops at a dual "
         "residual of 1e-10 relative or when it stops improving (no 1% gain in 5 iterations), at most 100 "
         "iterations; the best iterate is the reference";
}

ReferenceSolver::ReferenceSolver(const Problem& prob, const Params& p) : prob_(prob), ds_(prob) {
  const MethodInfo* m = find_method("cholmod");
  if (!m || !m->available) throw Error("reference: the direct solver 'cholmod' is not available");
  direct_ = make_linear_solver("cholmod", p);
}

ReferenceSolution ReferenceSolver::solve(const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& alpha_tilde) {
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
      out.status = "failed";
      break;
    }
    if (dual < best) {
      best = dual;
      out.x = x;
      out.dual_residual = dual;
      out.relative_dual_residual = r0 > 0 ? dual / r0 : 0;
    }
    if (dual <= target_relative * r0 || dual == 0) {
      out.status = "converged";
      break;
    }
    // Stagnation: the best value gained less than 1% over the last window of iterations.
    if (best < 0.99 * best_at_window_start) {
      best_at_window_start = best;
      since_gain = 0;
    } else if (++since_gain >= stagnation_window) {
      out.status = "stagnated";
      break;
    }
    if (it >= max_iterations) {
      out.status = "max_iterations";
      break;
    }
    ds_.fill(state, alpha_tilde);
    direct_->setup(ds_.A(), first_setup_ ? SetupKind::Structure : SetupKind::Values, SetupContext{0, 0, it});
    first_setup_ = false;
    const LinearStats st = direct_->solve(b, dlambda);
    ++out.iterations;
    if (st.status == LinearStatus::breakdown || !dlambda.allFinite()) {
      out.status = "failed";
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
  double sum = 0;
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (int p = 0; p < static_cast<int>(a.cols()); ++p)
    if (w[p] > 0) sum += (a.col(p) - b.col(p)).squaredNorm() / w[p];
  return std::sqrt(sum);
}

}  // namespace xb
