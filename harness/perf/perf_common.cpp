#include "perf_common.hpp"

#include "../../problems/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../common.hpp"
#include "../stepper.hpp"

namespace xb::perf {

Params case_params(const SceneCase& c, const std::vector<std::string>& extra_sets) {
  std::vector<std::string> sets = c.sets;
  sets.insert(sets.end(), extra_sets.begin(), extra_sets.end());
  return resolve_params(c.scene, sets);
}

CapturedSystem capture_system(const SceneCase& c, int frame, int iteration, const std::vector<std::string>& extra_sets,
                              const std::string& driver) {
  Params p = case_params(c, extra_sets);
  if (p.frames <= frame) p.frames = frame + 1;
  if (p.max_iterations < iteration) p.max_iterations = iteration;
  const Problem prob = build_problem(p);
  CapturedSystem out;
  out.label = c.label + "/f" + std::to_string(frame) + "i" + std::to_string(iteration);
  bool got = false;
  RunOptions opt;
  opt.on_system = [&](int f, int, int it, const SparseMatrix& A, const Vector& b) {
    if (f != frame || it != iteration) return false;
    out.A = A;
    out.b = b;
    got = true;
    return true;
  };
  const RunResult res = run_simulation(prob, p, driver, opt);
  if (!got)
    throw Error("perf: could not capture " + out.label + " (the " + driver + " run ended with status " + res.status +
                (res.message.empty() ? "" : ": " + res.message) + ")");
  return out;
}

std::vector<std::string> available_linear_solvers() {
  std::vector<std::string> v;
  for (const auto& m : methods())
    if (!m.local && m.available) v.push_back(m.name);
  return v;
}

std::vector<std::string> local_methods() {
  std::vector<std::string> v;
  for (const auto& m : methods())
    if (m.local && m.available) v.push_back(m.name);
  return v;
}

std::vector<std::string> unavailable_methods() {
  std::vector<std::string> v;
  for (const auto& m : methods())
    if (!m.available) v.push_back(m.name);
  return v;
}

}  // namespace xb::perf
