#include "smoother.hpp"

#include "../../../core/error.hpp"

#include <cmath>

namespace xb::amg {

void Smoother::set_lambda_max(double) {
  throw Error("amg.jacobi_omega=level0: smoother '" + name() + "' has no lambda_max(D^-1 A) to share (use jacobi or chebyshev)");
}

void PolynomialSmoother::check_lambda(const SparseMatrix& A) const {
  if (!(relax_.lambda > 0) || !std::isfinite(relax_.lambda))
    throw Error("amg.smoother=" + opt_.kind + ": no positive spectral radius estimate on a level of " +
                std::to_string(A.rows()) + " rows (matrix not positive definite?)");
}

}  // namespace xb::amg
