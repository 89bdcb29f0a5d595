#include "cholmod_settings.hpp"

namespace xb {

const SettingTable<CholmodSettings>& cholmod_settings() {
  using S = CholmodSettings;
  static const SettingTable<S> table = {
      setting("cholmod.refactor", "always (factorise every matrix) | lagged (an earlier factor preconditions CG; factorise again at a frame's start or past cholmod.lagged_max_iterations)", &S::refactor, {"always", "lagged"}).applies({on("cholmod")}),
      setting("cholmod.lagged_max_iterations", "lagged: CG iterations with an old factor before it is factorised again", &S::lagged_max_iterations, 1, 1e9).applies({on("cholmod").where("cholmod.refactor=lagged")}),
  };
  return table;
}

}  // namespace xb
