#include "capture.hpp"

#include "simulation.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"

#include <algorithm>

namespace xb {

CapturedSystem capture_system(Params p, const std::string& driver, int frame, int substep, int iteration,
                              double time_budget, std::function<void(const IterationProgress&)> on_iteration) {
  if (p.frames < frame + 1) p.frames = frame + 1;
  const Problem prob = build_problem(p);
  CapturedSystem sys;
  bool captured = false;
  RunOptions opt;
  opt.time_budget = time_budget;
  opt.on_iteration = std::move(on_iteration);
  opt.on_system = [&](const SystemView& v) {
    if (v.frame != frame || v.substep != substep || v.iteration != iteration) return false;
    sys.A = v.A;
    sys.A.makeCompressed();
    sys.b = v.b;
    sys.graph = constraint_graph(prob);
    sys.grad = v.state.grad;
    sys.alpha_tilde = v.alpha_tilde;
    sys.x = v.x;
    captured = true;
    return true;
  };
  const RunResult res = run_simulation(prob, p, driver, opt);
  if (captured) return sys;
  // Where the run stopped, from its log.
  long long last_it = -1;
  for (size_t k = 0; k < res.log.frame.size(); ++k)
    if (res.log.frame[k] == frame && res.log.substep[k] == substep) last_it = std::max(last_it, res.log.iteration[k]);
  std::string why = "run status " + res.status + (res.message.empty() ? "" : " (" + res.message + ")");
  if (last_it >= 0 && (res.status == "ok" || res.status == "max_iterations"))
    why = "that substep converged after " + std::to_string(last_it) +
          " outer iterations, so its last assembled system is iteration " + std::to_string(last_it - 1);
  throw Error("capture: the " + driver + " run ended before frame " + std::to_string(frame) + ", substep " +
              std::to_string(substep) + ", iteration " + std::to_string(iteration) + " was reached: " + why);
}

}  // namespace xb
