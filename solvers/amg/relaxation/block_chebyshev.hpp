// Jacobi and Chebyshev smoothers in D⁻¹A with D the node-block diagonal of a block system
// (3×3 particle blocks on K, an aggregate's QR block on coarse levels): the polynomial smoothers
// of smoothers.hpp with a particle's x, y, z scaled together. λ_max(D⁻¹A) from Lanczos in the D
// inner product (block_diagonal.hpp); a refresh warm-starts it from the previous top Ritz vector.
//  block_jacobi:    x += D⁻¹(b − Ax)/λ_max
//  block_chebyshev: the degree-3 Chebyshev polynomial on [λ/30, 1.1λ]
#pragma once

#include "block_diagonal.hpp"
#include "smoother.hpp"

#include <memory>

namespace xb::amg {

// opt.kind block_jacobi or block_chebyshev; blocks: A's node blocks (not owned, outliving the
// smoother), which its Lanczos and relaxation steps then read A by, or null. Throws xb::Error if a
// diagonal block is not positive definite or no positive λ_max estimate is found.
std::unique_ptr<Smoother> make_block_diagonal_smoother(const SmootherOptions& opt, const SparseMatrix& A,
                                                       const NodeLayout& nodes, const BlockOperator* blocks);

}  // namespace xb::amg
