#include "hypre_settings.hpp"

namespace xb {

const SettingTable<HypreSettings>& hypre_settings() {
  using S = HypreSettings;
  static const SettingTable<S> table = {
      setting("hypre.coarsening", "BoomerAMG coarsening", &S::coarsening, {"HMIS", "PMIS", "Falgout"}),
      setting("hypre.interpolation", "BoomerAMG interpolation", &S::interpolation, {"ext+i", "classical", "direct", "multipass"}),
      setting("hypre.relaxation", "BoomerAMG relaxation", &S::relaxation, {"l1-jacobi", "jacobi", "hgs", "l1-gs", "chebyshev"}),
      setting("hypre.aggressive_levels", "levels of aggressive coarsening", &S::aggressive_levels, 0, 25),
      setting("hypre.max_levels", "BoomerAMG maximum levels", &S::max_levels, 1, 64),
      setting("hypre.reuse", "Values setups: none (full BoomerAMG setup) | hierarchy (keep the last one until a rebuild every amg.setup_interval frames)", &S::reuse, {"none", "hierarchy"}),
  };
  return table;
}

}  // namespace xb
