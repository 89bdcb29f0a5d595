#include "muelu_settings.hpp"

namespace xb {

const SettingTable<MueluSettings>& muelu_settings() {
  using S = MueluSettings;
  static const SettingTable<S> table = {
      setting("muelu.algorithm", "auto (unsmoothed dual, sa primal) | unsmoothed | sa (smoothed aggregation)", &S::algorithm, {"auto", "unsmoothed", "sa"}).applies({on("muelu").also_solve()}),
      setting("muelu.smoother", "chebyshev | jacobi | gs | sgs", &S::smoother, {"chebyshev", "jacobi", "gs", "sgs"}).applies({on("muelu").also_solve()}),
      setting("muelu.smoother_sweeps", "smoother sweeps", &S::smoother_sweeps, 1, 100).applies({on("muelu").also_solve()}),
      setting("muelu.coarse_size", "coarse size", &S::coarse_size, 1, 1e9).applies({on("muelu").also_solve()}),
      setting("muelu.reuse", "Values setups: MueLu reuse: type none | tP | RP (full rebuild every amg.setup_interval frames)", &S::reuse, {"none", "tP", "RP"}).applies({on("muelu")}),
  };
  return table;
}

}  // namespace xb
