#include "hypre_settings.hpp"

namespace xb {

const SettingTable<HypreSettings>& hypre_settings() {
  using S = HypreSettings;
  static const SettingTable<S> table = {
      setting("hypre.coarsening", "BoomerAMG coarsening", &S::coarsening, {"HMIS", "PMIS", "Falgout"}).applies({on("hypre").also_solve()}),
      setting("hypre.interpolation", "BoomerAMG interpolation", &S::interpolation, {"ext+i", "classical", "direct", "multipass"}).applies({on("hypre").also_solve()}),
      setting("hypre.relaxation", "BoomerAMG relaxation", &S::relaxation, {"l1-jacobi", "jacobi", "hgs", "l1-gs", "chebyshev"}).applies({on("hypre").also_solve()}),
      setting("hypre.aggressive_levels", "levels of aggressive coarsening", &S::aggressive_levels, 0, 25).applies({on("hypre").also_solve()}),
      setting("hypre.max_levels", "BoomerAMG maximum levels", &S::max_levels, 1, 64).applies({on("hypre").also_solve()}),
      setting("hypre.reuse", "Values setups: none (full BoomerAMG setup) | hierarchy (keep the last one until a rebuild every amg.setup_interval frames)", &S::reuse, {"none", "hierarchy"}).applies({on("hypre")}),
  };
  return table;
}

}  // namespace xb
