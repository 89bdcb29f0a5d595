// The two measures a simulation run logs per evaluation besides the dual residual
// (harness/io/run_result.hpp, IterationLog::primal_residual and IterationLog::energy).
#pragma once

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <Eigen/Dense>

namespace xb {

// ‖M(x − x̃) − ∇Cᵀλ‖₂ over free particles; `work` is scratch (∇Cᵀλ).
double primal_residual(const Problem& prob, const DualSystem& ds, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& x_pred, const Eigen::VectorXd& lambda, Eigen::Matrix3Xd& work);

// ‖x − x̃‖²_M/(2h²) + Σ C²/(2α) over constraints with α > 0: the energy one substep minimises.
double incremental_energy(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                          const Eigen::Matrix3Xd& x_pred, double h);

}  // namespace xb
