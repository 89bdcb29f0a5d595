// Preconditioned conjugate gradients (Algorithm 3 of the supplemental with a generic
// preconditioner): from x₀ = 0 to ‖r‖₂ ≤ tol·‖b‖₂, logging ‖r_k‖₂ with a time stamp.
#pragma once

#include "../linear_solver.hpp"

#include <functional>

namespace xb {

// The recurrence residual is checked against tol; on exit the true residual b − Ax is
// recomputed and reported as final_relative_residual (so a drifted recurrence cannot
// pass for converged). A null preconditioner means plain CG. `rel` (if set) measures the
// relative residual instead of ‖r‖₂/‖b‖₂; the residual history then holds rel(r)·‖b‖₂.
// natural_norm: stop on the preconditioned norm instead, √(r_kᵀM⁻¹r_k) ≤ tol·√(r_0ᵀM⁻¹r_0)
// (linear.stop_norm = energy; the history still holds the residual above).
LinearStats pcg(const SparseMatrix& A, const Vector& b, Vector& x, const Preconditioner& precond, double tol,
                int max_iterations, const RelativeResidual& rel = nullptr, bool natural_norm = false);

}  // namespace xb
