// The settings every solver is built from: the linear solve's (linear.*), the random seed of
// randomized setups, and each solver family's own table (amg.*, hypre.*, muelu.*, xpbd.*).
// Solvers take this struct, never the harness's Params; the MPI workers receive it as text.
#pragma once

#include "amg/amg_settings.hpp"
#include "local/xpbd_settings.hpp"
#include "mpi/hypre_settings.hpp"
#include "mpi/muelu_settings.hpp"

namespace xb {

struct LinearSettings {
  double tol = 1e-8;  // ‖r‖₂ ≤ tol·‖b‖₂
  int max_iterations = 1000;
};

struct SolverSettings {
  int seed = 1;  // random starts of near-kernel candidates and λ_max estimates
  LinearSettings linear;
  amg::AmgOptions amg;
  HypreSettings hypre;
  MueluSettings muelu;
  XpbdSettings xpbd;
};

const SettingTable<SolverSettings>& solver_settings();

}  // namespace xb
