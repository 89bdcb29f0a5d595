#include "stepper_settings.hpp"

#include "../problems/primal_system.hpp"

namespace xb {

const SettingTable<StepperSettings>& stepper_settings() {
  using S = StepperSettings;
  constexpr double inf = 1e300;
  static const SettingTable<S> table = {
      setting("max_iterations", "outer iterations per substep", &S::max_iterations, 1, 1e9),
      setting("rtol", "outer stop: dual residual relative to iteration 0", &S::rtol, 0, inf),
      setting("atol", "outer stop: absolute dual residual", &S::atol, 0, inf),
      setting("omega", "global step size x += omega M^-1 grad C^T dlambda", &S::omega, 1e-300, 2),
      setting("residual_metric", "dual residual of the stop test: true (|C(x_k) + alpha~ lambda_k|) | authors (|C(x~) + alpha~ lambda_k| local, |C(x_k-1) + alpha~ lambda_k| global)", &S::residual_metric, {"true", "authors"}),
      setting("step", "global step: fixed (x += omega M^-1 grad C^T dlambda) | line_search (lambda += dlambda, then x += t dx with t = 1, 1/2, ... the first that lowers |C(x) + alpha~ lambda|)", &S::step, {"fixed", "line_search"}),
      setting("threads", "OpenMP threads (0 = default)", &S::threads, 0, 4096),
      setting("form", "linear step of global methods: dual (A dlambda = b) | primal (K dx = J^T alpha~^-1 b, every alpha~ > 0) | auto (primal when every alpha~ > 0)", &S::form, form_choices()),
  };
  return table;
}

}  // namespace xb
