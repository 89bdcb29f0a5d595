// The incremental energy a simulation run logs per evaluation (harness/io/run_result.hpp,
// IterationLog::energy) and Newton's line search reads (harness/sim/newton.hpp, which also has the
// primal residual g).
#pragma once

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <Eigen/Dense>

namespace xb {

// ‖x − x̃‖²_M/(2h²) + Σ C²/(2α) over constraints with α > 0: the energy one substep minimises.
double incremental_energy(const Problem& prob, const ConstraintState& s, const Eigen::Matrix3Xd& x,
                          const Eigen::Matrix3Xd& x_pred, double h);

}  // namespace xb
