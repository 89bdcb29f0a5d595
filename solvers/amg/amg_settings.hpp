// The in-house AMG's settings (mgpbd): the amg.* keys. amg.setup_interval also paces the lazy
// setup of hypre and MueLu (solvers/setup_policy.hpp).
#pragma once

#include "../../core/settings.hpp"

#include <string>

namespace xb {

struct AmgSettings {
  double strength_threshold = 0.25;
  std::string aggregation = "standard";
  std::string near_kernel = "auto";  // auto (ones dual, rigid primal) | ones | gs | gs_authors | rigid
  std::string coarse_solver = "direct";   // direct (Cholesky) | smoother (the level's smoother from zero)
  std::string jacobi_omega = "per_level";  // per_level | level0 (lambda_max of level 0 on every level)
  int near_kernel_sweeps = 20;
  int near_kernel_vectors = 1;
  int near_kernel_extra = 0;  // rigid: relaxed random vectors appended to the rigid modes
  std::string prolongator = "auto";  // auto (tentative dual, smoothed primal) | tentative | smoothed
  double nodal_strength_threshold = 0.0;         // block systems (primal K), level 0
  double coarse_nodal_strength_threshold = 0.1;  // levels >= 1 (< 0: the level-0 value)
  double min_coarsening = 4;  // fewer nodes per aggregate than this → redone at theta 0 (levels >= 1), then merged
  double drop_tolerance = 1e-10;  // block level 0: relative size of a node block treated as zero
  std::string prolongator_diagonal = "block";    // D of the smoothed P: block | scalar
  std::string smoother = "auto";  // auto (chebyshev dual, block_chebyshev primal) | jacobi | chebyshev | gs | block_gs | block_jacobi | block_chebyshev
  int smoother_sweeps = 0;        // 0: auto (1)
  int chebyshev_degree = 0;       // 0: auto (3 dual, the authors'; 4 primal)
  int setup_interval = 20;        // frames between rebuilds of aggregates and P
  int max_coarse = 400;
  int max_levels = 10;
  std::string precision = "double";  // storage of the V-cycle: double | single (float matrices and vectors; CG stays double)
};

const SettingTable<AmgSettings>& amg_settings();

}  // namespace xb
