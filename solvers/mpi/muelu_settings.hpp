// Trilinos MueLu's settings: the muelu.* keys (their translation into a MueLu parameter list is
// in muelu.cpp: muelu_parameter_text).
#pragma once

#include "../../core/settings.hpp"

#include <string>

namespace xb {

struct MueluSettings {
  std::string algorithm = "auto";     // auto (unsmoothed dual, sa primal) | unsmoothed | sa
  std::string smoother = "chebyshev";  // chebyshev | jacobi | gs | sgs
  int smoother_sweeps = 1;
  int coarse_size = 400;
  std::string reuse = "tP";  // none | tP | RP: MueLu "reuse: type" for Values setups
};
const SettingTable<MueluSettings>& muelu_settings();

}  // namespace xb
