// hypre BoomerAMG's settings: the hypre.* keys (their translation into BoomerAMG calls is in
// hypre.cpp: hypre_options).
#pragma once

#include "../../core/settings.hpp"

#include <string>

namespace xb {

struct HypreSettings {
  std::string coarsening = "HMIS";      // HMIS | PMIS | Falgout
  std::string interpolation = "ext+i";  // ext+i | classical | direct | multipass
  std::string relaxation = "l1-jacobi";  // l1-jacobi | jacobi | hgs | l1-gs | chebyshev
  int aggressive_levels = 0;
  int max_levels = 25;
  std::string reuse = "none";  // none | hierarchy (keep the last hierarchy for Values setups)
};
const SettingTable<HypreSettings>& hypre_settings();

}  // namespace xb
