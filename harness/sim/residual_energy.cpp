#include "residual_energy.hpp"

#include "../../core/reduce.hpp"

#include <cmath>

namespace xb {

// Both sums over fixed chunks (core/reduce.hpp): E, and every line-search decision on it, is the
// same for any thread count.
double incremental_energy(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                          const Eigen::Matrix3Xd& x_pred, double h) {
  const Eigen::VectorXd& w = prob.particles.w;
  const double kin = deterministic_sum(x.cols(), [&](long p) {
    return w[p] > 0 ? (x.col(p) - x_pred.col(p)).squaredNorm() / w[p] : 0.0;
  });
  const double pot = deterministic_sum(prob.num_constraints(), [&](long j) {
    const double a = prob.compliance(static_cast<int>(j));
    return a > 0 ? s.C[j] * s.C[j] / a : 0.0;
  });
  return kin / (2 * h * h) + pot / 2;
}

}  // namespace xb
