#include "capture.hpp"

#include "simulation.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"

#include <algorithm>

namespace xb {

// A captured system is XPBD's step: A Δλ = −(C + α̃λ), and J, α̃, M from which `solve`, the Python
// System and the GPU export rebuild K = M + Jᵀα̃⁻¹J and its right-hand side. Under these keys the
// run solves another system (element Hessians in K, g on the right) that no reader could rebuild
// from the file, so capture refuses rather than write a system the run never solved.
void check_capturable(const Params& p) {
  std::string key;
  if (p.step == "newton") key = "step=newton";
  else if (p.geometric_stiffness != "none") key = "xpbd.geometric_stiffness=" + p.geometric_stiffness;
  else if (p.primal_residual != "zero") key = "xpbd.primal_residual=" + p.primal_residual;
  if (!key.empty())
    throw Error("capture: " + key + " solves a system other than XPBD's A dlambda = -(C + alpha~ lambda), which is "
                "what capture writes (with J to rebuild K = M + J^T alpha~^-1 J); capture with step=fixed or "
                "line_search, xpbd.geometric_stiffness=none and xpbd.primal_residual=zero");
}

CapturedSystem capture_system(Params p, const std::string& driver, int frame, int substep, int iteration,
                              double time_budget, std::function<void(const IterationProgress&)> on_iteration) {
  check_capturable(p);
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
