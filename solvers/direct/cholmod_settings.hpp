// CHOLMOD's settings: the cholmod.* keys.
#pragma once

#include "../../core/settings.hpp"

#include <string>

namespace xb {

struct CholmodSettings {
  // always: factorise every matrix (one exact solve per outer iteration). lagged: keep the factor
  // of an earlier matrix as the preconditioner of CG (to the linear tolerance of the step), and
  // factorise again at the first setup of a frame or when that CG needs more than
  // lagged_max_iterations.
  std::string refactor = "always";
  int lagged_max_iterations = 30;
};

const SettingTable<CholmodSettings>& cholmod_settings();

}  // namespace xb
