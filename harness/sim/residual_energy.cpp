#include "residual_energy.hpp"

#include <cmath>

namespace xb {

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

}  // namespace xb
