// Strength of connection (Eq. 26 of the supplemental, pyamg's 'symmetric' rule): row i keeps
// A_ij (j ≠ i) where |A_ij| ≥ θ_s·sqrt(|A_ii||A_jj|), and always its diagonal. θ_s = 0 keeps every
// stored entry. The result S has A's values on the kept entries; aggregation reads its pattern.
#pragma once

#include "../../core/sparse.hpp"

namespace xb::amg {

// Throws xb::Error for θ < 0 or a non-square A.
SparseMatrix strength_symmetric(const SparseMatrix& A, double theta);

}  // namespace xb::amg
