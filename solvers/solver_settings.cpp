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
      setting("linear.forcing", "inner tolerance per outer iteration: fixed (linear.tol) | eisenstat_walker (eta_k = gamma (r_k/r_k-1)^alpha, safeguarded, in [linear.tol, linear.forcing_max])", &LinearSettings::forcing, {"fixed", "eisenstat_walker"}),
      setting("linear.forcing_max", "eisenstat_walker: the largest inner tolerance (also the first of each substep)", &LinearSettings::forcing_max, 1e-300, 0.999),
      setting("linear.forcing_gamma", "eisenstat_walker: gamma of choice 2", &LinearSettings::forcing_gamma, 1e-300, 1),
      setting("linear.forcing_alpha", "eisenstat_walker: alpha of choice 2", &LinearSettings::forcing_alpha, 1.0 + 1e-12, 2),
      setting("linear.stop_norm", "norm of the linear stop test: dual (|J M^-1 r_K| in the primal form) | primal (the solved system's |r|_2) | energy (preconditioned norm sqrt(r'M^-1 r))", &LinearSettings::stop_norm, {"dual", "primal", "energy"}),
  };
  append_part(t, linear, [](S& s) -> LinearSettings& { return s.linear; });
  append_part(t, amg_settings(), [](S& s) -> amg::AmgOptions& { return s.amg; });
  append_part(t, cholmod_settings(), [](S& s) -> CholmodSettings& { return s.cholmod; });
  append_part(t, hypre_settings(), [](S& s) -> HypreSettings& { return s.hypre; });
  append_part(t, muelu_settings(), [](S& s) -> MueluSettings& { return s.muelu; });
  append_part(t, xpbd_settings(), [](S& s) -> XpbdSettings& { return s.xpbd; });
  append_part(t, block_descent_settings(), [](S& s) -> BlockDescentSettings& { return s.block_descent; });
  return t;
}
}  // namespace

const SettingTable<SolverSettings>& solver_settings() {
  static const SettingTable<SolverSettings> table = make_table();
  return table;
}

}  // namespace xb
