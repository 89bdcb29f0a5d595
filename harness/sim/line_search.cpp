#include "line_search.hpp"

namespace xb {

LineSearchStep backtrack_dual_residual(const Problem& prob, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda,
                                       const Eigen::Matrix3Xd& dx, const Eigen::VectorXd& alpha_tilde, double current,
                                       ConstraintState& scratch, Eigen::Matrix3Xd& x_trial) {
  const Eigen::VectorXd stress = alpha_tilde.cwiseProduct(lambda);
  LineSearchStep s;
  for (double t = 1;; t *= 0.5) {
    x_trial = x + t * dx;
    evaluate_constraints(prob, x_trial, scratch);
    s.residual = (scratch.C + stress).norm();
    ++s.trials;
    // A NaN trial (an inverted or degenerate element) never counts as a decrease.
    if (s.residual < current) {
      s.t = t;
      s.decreased = true;
      return s;
    }
    if (t < line_search_min_step) {
      s.t = 0;
      return s;
    }
  }
}

}  // namespace xb
