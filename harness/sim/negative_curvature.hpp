// Directions of negative curvature of the exact Newton matrix K = M + Σ_j H_j (= h²∇²E, on the free
// dofs) from the elements' closed-form lowest modes (ElementHessians::lowest_mode: a tet's ARAP
// twist mode, ψ = 1 − 2/(σᵢ + σⱼ), a compressed distance's transverse direction). An element mode
// δx_j has curvature ψ/α̃ in its own element; in K it meets the mass and the neighbours' stiffness
// too, so its global Rayleigh quotient δx_jᵀKδx_j/δx_jᵀDδx_j is computed (K's rows on its 12 dofs).
// Any negative quotient proves K indefinite and bounds its smallest eigenvalue (relative to D)
// from above; the trust region's subproblem solvers use the most negative one as the hard case's
// direction and as the lower bound of Moré–Sorensen's shift, and the sum of the non-interacting
// ones (no row of one meets the other's dofs, so their curvatures add) as the direction along
// which every indefinite element moves at once.
#pragma once

#include "../../problems/element_hessians.hpp"
#include "../../problems/primal_system.hpp"
#include "../../problems/problem.hpp"
#include "../../core/sparse.hpp"

namespace xb {

struct NegativeCurvature {
  Vector best;           // the mode with the smallest quotient, ‖best‖_D = 1, gᵀbest ≤ 0 (empty: none negative)
  double smallest = 0;   // its quotient bestᵀK best (< 0), 0 where none
  Vector combined;       // Σ s_j δx_j/‖δx_j‖_D over non-interacting negative modes, s_j = −sign(gᵀδx_j), ‖·‖_D = 1
  int candidates = 0;    // element modes tried (the most negative elements first)
  int negative = 0;      // of them, negative in K
  int combined_modes = 0;
};

// K: the exact K (free dofs, PrimalSystem's order; `sys` gives the dof of each particle); D > 0 per
// dof; g = h²∇E per dof; eh holds the exact fill's smallest eigenvalues and the SVDs at x. At most
// `max_candidates` elements (by their own smallest eigenvalue, ascending) are tried. `held`: K's
// rows the step holds (contact's active bounds), left out of every mode.
NegativeCurvature negative_curvature(const Problem& prob, const ElementHessians& eh, const Eigen::Matrix3Xd& x,
                                     const Eigen::VectorXd& alpha_tilde, const PrimalSystem& sys, const SparseMatrix& K,
                                     const Vector& D, const Vector& g, const std::vector<int>& held, int max_candidates);

}  // namespace xb
