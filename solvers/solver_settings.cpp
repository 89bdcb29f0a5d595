#include "solver_settings.hpp"

namespace xb {

namespace {
SettingTable<SolverSettings> make_table() {
  using S = SolverSettings;
  SettingTable<S> t = {
      setting("seed", "random seed", &S::seed, 0, 2147483647.0),
  };
  const SettingTable<LinearSettings> linear = {
      setting("linear.tol", "linear solve: |r|_2 <= tol |b|_2", &LinearSettings::tol, 0, 1),
      setting("linear.max_iterations", "linear solve iteration limit", &LinearSettings::max_iterations, 1, 1e9),
  };
  append_part(t, linear, [](S& s) -> LinearSettings& { return s.linear; });
  append_part(t, amg_settings(), [](S& s) -> amg::AmgOptions& { return s.amg; });
  append_part(t, hypre_settings(), [](S& s) -> HypreSettings& { return s.hypre; });
  append_part(t, muelu_settings(), [](S& s) -> MueluSettings& { return s.muelu; });
  append_part(t, xpbd_settings(), [](S& s) -> XpbdSettings& { return s.xpbd; });
  return t;
}
}  // namespace

const SettingTable<SolverSettings>& solver_settings() {
  static const SettingTable<SolverSettings> table = make_table();
  return table;
}

}  // namespace xb
