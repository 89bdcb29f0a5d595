#include "line_search.hpp"

#include <limits>

namespace xb {

LineSearchStep backtrack_dual_residual(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda,
                                       const Eigen::Matrix3Xd& dx, const Eigen::VectorXd& dlambda,
                                       const Eigen::VectorXd& alpha_tilde, double current, ConstraintState& scratch,
                                       Eigen::Matrix3Xd& x_trial) {
  LineSearchStep best;
  best.residual = std::numeric_limits<double>::infinity();
  double t = 1;
  for (int k = 0; k <= line_search_max_halvings; ++k, t *= 0.5) {
    x_trial = x + t * dx;
    evaluate_constraints(prob, x_trial, scratch);
    const double r = (scratch.C + alpha_tilde.cwiseProduct(lambda + t * dlambda)).norm();
    ++best.trials;
    // A NaN trial (an inverted or degenerate element) never counts as a decrease.
    if (r < current) return {t, r, best.trials, true};
    if (r < best.residual) {
      best.t = t;
      best.residual = r;
    }
  }
  if (!(best.residual < std::numeric_limits<double>::infinity())) best.t = t * 2;  // all NaN: the smallest step
  return best;
}

}  // namespace xb
