// λ_max(D⁻¹A) by Lanczos in the D inner product, for any diagonal D (scalar or node blocks): the
// smoothers' and the smoothed prolongator's spectral bound.
#pragma once

#include "../../../core/sparse.hpp"

#include <functional>

namespace xb::amg {

struct BlockOperator;

// ‖x‖_D.
using DNorm = std::function<double(const Vector& x)>;
// w = D⁻¹Aq − a·q − β·q_prev (one Lanczos step's three-term recurrence).
using LanczosStep =
    std::function<void(const Vector& Aq, const Vector& q, const Vector& q_prev, double a, double beta, Vector& w)>;

// max(iterations, 10) steps (at most n) from v — a seeded random vector when v is empty or zero —
// and the largest Ritz value plus its residual bound. v becomes the top Ritz vector, the start of
// the next estimate (from the last Lanczos vector, nearly orthogonal to the top eigenvector, a
// refresh underestimated λ_max by up to 35% on coarse levels of K). NaN if the tridiagonal
// eigenproblem fails. blocks: A's node blocks, for its products (block_kernels.hpp), or null.
double lanczos_lambda_max(const SparseMatrix& A, Vector& v, int iterations, unsigned seed, const DNorm& dnorm,
                          const LanczosStep& step, const BlockOperator* blocks = nullptr);

// Upper estimate of λ_max(D⁻¹A) (A SPD): max(iterations, 10) Lanczos steps from v, largest Ritz
// value plus its residual bound, capped by Gershgorin's bound (v is updated to start the next
// estimate; a zero or wrongly sized v is replaced by a seeded random vector).
double estimate_lambda_max(const SparseMatrix& A, const Vector& inv_diag, Vector& v, int iterations,
                           unsigned seed = 1);

}  // namespace xb::amg
