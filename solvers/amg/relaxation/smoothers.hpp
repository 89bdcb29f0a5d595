// The smoother kinds of the V-cycle (amg.smoother), and the one place their names map to code
// (make_smoother). The interface is smoother.hpp; one file per kind:
//  jacobi:    (chebyshev.hpp) x += ω D⁻¹(b − Ax), ω = 1/λ_max(D⁻¹A) (the authors' 2/(λ_max+λ_min) with
//             λ_min = λ_max). A fixed ω such as 0.72 diverges on XPBD matrices, where
//             ρ(D⁻¹A) reaches 4–11 (scripts/dual_spectrum.py on captured systems), so λ_max is estimated.
//  chebyshev: (chebyshev.hpp) Chebyshev polynomial in D⁻¹A on [ρ/30, 1.1ρ] (the authors' cloth setting, degree 3),
//             ρ estimated per level (the authors reuse level 0's; per level is cheap and safer).
//  gs:        (gauss_seidel.hpp) multicolour Gauss–Seidel, forward sweeps before, backward sweeps after.
//  block_gs, block_jacobi, block_chebyshev: the same with D the node blocks of a block system
//             (block_gs.hpp, block_chebyshev.hpp); on a scalar layout D is the diagonal.
// λ_max(D⁻¹A) comes from Lanczos in the D inner product (lanczos.hpp); a values-only refresh
// warm-starts it from the previous top Ritz vector.
#pragma once

#include "../node_layout.hpp"
#include "smoother.hpp"

#include <memory>
#include <string>
#include <vector>

namespace xb::amg {

struct BlockOperator;

// The smoother kinds make_smoother knows: the amg.smoother table's choices (with auto) and its
// messages read this one list.
const std::vector<std::string>& smoother_kinds();

// `nodes`: the level's node layout (the block kinds' D; scalar: 1×1 blocks). `blocks`: A's node
// blocks in that layout (not owned, outliving the smoother) for block_jacobi and block_chebyshev
// to read A by, or null. Throws xb::Error naming amg.smoother for an unknown kind.
std::unique_ptr<Smoother> make_smoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes = {},
                                        const BlockOperator* blocks = nullptr);

}  // namespace xb::amg
