#include "chebyshev.hpp"

#include "lanczos.hpp"

#include "../../kernels.hpp"

namespace xb::amg {

DiagonalSmoother::DiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A)
    : PolynomialSmoother(opt, opt.kind == "chebyshev") {
  update(A, opt_.power_iterations);
}

void DiagonalSmoother::update(const SparseMatrix& A, int lanczos_steps) {
  relax_.inv_diag = inverse_diagonal(A);
  relax_.lambda = estimate_lambda_max(A, relax_.inv_diag, eigvec_, lanczos_steps, opt_.seed);
  check_lambda(A);
}

}  // namespace xb::amg
