#include "perf_common.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../cli/run_setup.hpp"
#include "../io/run_record.hpp"
#include "../sim/capture.hpp"

namespace xb::perf {

Params case_params(const SceneCase& c, const std::vector<std::string>& extra_sets) {
  std::vector<std::string> sets = c.sets;
  sets.insert(sets.end(), extra_sets.begin(), extra_sets.end());
  return resolve_params(c.scene, sets);
}

LabelledSystem capture_case(const SceneCase& c, int frame, int iteration, const std::vector<std::string>& extra_sets,
                            const std::string& driver) {
  Params p = case_params(c, extra_sets);
  if (p.max_iterations < iteration + 1) p.max_iterations = iteration + 1;
  LabelledSystem out;
  static_cast<CapturedSystem&>(out) = capture_system(p, driver, frame, 0, iteration);
  out.label = c.label + "/f" + std::to_string(frame) + "i" + std::to_string(iteration);
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
