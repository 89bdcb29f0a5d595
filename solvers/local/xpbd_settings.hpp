// The local XPBD sweeps' settings: the xpbd.* keys.
#pragma once

#include "../../core/settings.hpp"

namespace xb {

struct XpbdSettings {
  double position_relaxation = 0.1;  // xpbd-authors: x += this·M⁻¹∇CᵀΔλ while λ takes the full Δλ
  double jacobi_relaxation = 0;      // xpbd-jacobi: λ += ωJ·Δλ, x += ωJ·M⁻¹∇CᵀΔλ; 0 = 1/(most constraints on one particle)
};

const SettingTable<XpbdSettings>& xpbd_settings();

}  // namespace xb
