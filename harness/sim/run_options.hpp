// What a simulation run is given besides the problem and the parameters (harness/sim/simulation.hpp):
// the options and the views its callbacks receive.
#pragma once

#include "../params.hpp"
#include "../../problems/problem.hpp"
#include "../../core/sparse.hpp"
#include "../io/run_result.hpp"
#include "../io/state_io.hpp"

#include <functional>
#include <string>

namespace xb {

// One global outer iteration's linear step, as `capture` sees it: the dual system (A is filled
// in either form) and what the primal form is built from.
struct SystemView {
  int frame, substep, iteration;
  const SparseMatrix& A;
  const Vector& b;
  const ConstraintState& state;
  const Eigen::VectorXd& alpha_tilde;
  const Eigen::Matrix3Xd& x;
};

// Where a run stands, after each evaluation of the dual residual (RunOptions::on_iteration).
struct IterationProgress {
  int frame, first_frame, frames;  // frames: how many the run takes, from first_frame
  int substep, substeps;
  int iteration, max_iterations;
  double relative_dual_residual;
};

struct RunOptions {
  double time_budget = 0;  // s, 0 = none; a run past it ends with status over_budget
  // Solve every substep also by the reference method (harness/sim/reference.hpp) and log the
  // position error per outer iteration. Its time is excluded from wall_time and time_budget.
  bool reference = false;
  // With reference: read each substep's reference from this file where it holds one of the same
  // problem and x̃, else compute it and add it there (harness/sim/reference_store.hpp); "" = none.
  std::string reference_file;
  // Bytes the process's resident set may reach; past it, checked before every outer iteration,
  // the run ends with status out_of_memory (0 = none). `run --memory-limit` also caps the data
  // segment there, so that an allocation past it fails inside the run (out_of_memory too).
  double memory_limit = 0;
  // Called with the system of every global outer iteration before it is solved; returning true
  // ends the run (used by `capture`).
  std::function<bool(const SystemView&)> on_system;
  // Called after every evaluation of the dual residual (live progress: harness/cli/progress.hpp).
  std::function<void(const IterationProgress&)> on_iteration;
  // Called after every frame with the positions (for mesh output).
  std::function<void(int frame, const Eigen::Matrix3Xd& x)> on_frame;
  // Called after every frame with the state the next frame starts from (for --save-state).
  std::function<void(const SimState&)> on_state;
  // Start from this state (positions, velocities; frames numbered from its frame) instead of
  // the scene's start. Its particle count must match the problem's.
  const SimState* initial_state = nullptr;
};

}  // namespace xb
