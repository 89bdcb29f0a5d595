#include "xpbd_settings.hpp"

namespace xb {

const SettingTable<XpbdSettings>& xpbd_settings() {
  using S = XpbdSettings;
  static const SettingTable<S> table = {
      setting("xpbd.position_relaxation", "xpbd-authors: x += this * M^-1 grad C^T dlambda (lambda takes the full dlambda)", &S::position_relaxation, 1e-300, 2).applies({on("xpbd-authors")}),
      setting("xpbd.jacobi_relaxation", "xpbd-jacobi relaxation of dlambda and dx (0 = 1/max constraints per particle)", &S::jacobi_relaxation, 0, 2).applies({on("xpbd-jacobi")}),
  };
  return table;
}

}  // namespace xb
