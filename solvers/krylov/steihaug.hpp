// Steihaug–Toint truncated conjugate gradients for the trust-region subproblem
//   min m(p) = gᵀp + ½pᵀKp   subject to ‖p‖_P ≤ Δ,
// K symmetric and possibly indefinite, P the preconditioner's SPD matrix (z = P⁻¹r is what is
// applied; P = I without one), whose norm is the region's (Steihaug 1983, Toint 1981;
// Nocedal–Wright, Numerical Optimization, Algorithm 7.2; Conn–Gould–Toint, Trust-Region Methods,
// §7.5.1). PCG on Kp = −g from p = 0 until
//   interior            ‖r‖₂ ≤ tol·‖g‖₂ inside the region (the inexact Newton step);
//   negative_curvature  a direction d with dᵀKd ≤ 0: the model falls without bound along it, so the
//                       step goes along d to the boundary (where plain PCG reports a breakdown);
//   boundary            the next CG iterate would leave the region: the step stops on it;
//   max_iterations      the last iterate, inside.
// ‖p‖_P grows monotonically along the CG iterates; it and the cross terms pᵀPd, dᵀPd follow from
// CG's own recurrences, without P.
#pragma once

#include "../linear_solver.hpp"

namespace xb {

enum class SteihaugExit { interior, boundary, negative_curvature, max_iterations };
const char* to_string(SteihaugExit e);

struct SteihaugResult {
  Vector p;                  // the step
  SteihaugExit exit = SteihaugExit::interior;
  int iterations = 0;        // products with K
  double model = 0;          // m(p) = gᵀp + ½pᵀKp, from one product Kp at the end
  double norm = 0;           // ‖p‖_P (the recurrences')
  double curvature = 0;      // negative_curvature: dᵀKd/dᵀPd of the direction that had it
  Vector Kp;                 // K p (the product behind `model`)
};

// K must be square and match g; radius > 0. A null preconditioner is P = I.
SteihaugResult steihaug_toint(const SparseMatrix& K, const Vector& g, double radius, const Preconditioner& precond,
                              double tol, int max_iterations);

// τ ≥ 0 with ‖p + τd‖² = radius², from ‖p‖² = pp, pᵀd = pd, ‖d‖² = dd in one inner product (pp ≤ radius²).
double step_to_boundary(double pp, double pd, double dd, double radius);

}  // namespace xb
