// The jacobi and chebyshev smoothers in D⁻¹A with D the scalar diagonal (amg.smoother = jacobi |
// chebyshev; their block forms are block_chebyshev.hpp):
//  jacobi:    x += ω D⁻¹(b − Ax), ω = 1/λ_max(D⁻¹A);
//  chebyshev: the Chebyshev polynomial in D⁻¹A on [λ/30, 1.1λ], degree amg.chebyshev_degree.
// λ_max from Lanczos (lanczos.hpp), estimated per level at setup and warm-started at a refresh.
#pragma once

#include "smoother.hpp"

namespace xb::amg {

class DiagonalSmoother final : public PolynomialSmoother {
 public:
  DiagonalSmoother(const SmootherOptions& opt, const SparseMatrix& A);
  void refresh(const SparseMatrix& A) override { update(A, opt_.refresh_power_iterations); }
  void set_lambda_max(double lambda) override { relax_.lambda = lambda; }

 private:
  void update(const SparseMatrix& A, int lanczos_steps);
};

}  // namespace xb::amg
