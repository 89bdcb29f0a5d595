#include "key_check.hpp"

#include "../core/error.hpp"
#include "../problems/scene.hpp"
#include "../solvers/linear_solver.hpp"

#include <memory>
#include <set>

namespace xb {

namespace {
const ParamField& field(const std::string& key) {
  const ParamField* f = find_param(key);
  if (!f) throw Error("unknown parameter '" + key + "'");
  return *f;
}

// A site that knows only the scene: it stands for every run of it (any method, form, step).
RunSite scene_site(const Params& p) {
  RunSite s;
  s.value = [scene = p.scene](const std::string& key) -> std::optional<std::string> {
    if (key == "scene") return scene;
    return std::nullopt;
  };
  return s;
}
}  // namespace

std::string resolved_form(const Params& p, const std::string& method) {
  const MethodInfo* m = find_method(method);
  if (!m || m->local) return "";
  if (p.form != "auto") return p.form;
  return every_constraint_compliant(p) ? "primal" : "dual";
}

RunSite run_site(const CommandRun& run) {
  RunSite s;
  const MethodInfo* m = find_method(run.method);
  s.method = run.method;
  s.local = m && m->local;
  s.python = run.method.rfind("py:", 0) == 0;
  s.form = run.solve ? run.form : resolved_form(run.params, run.method);
  s.reference = run.reference;
  s.solve = run.solve;
  auto p = std::make_shared<const Params>(run.params);
  s.value = [p](const std::string& key) -> std::optional<std::string> { return param_to_string(*p, field(key)); };
  return s;
}

void check_keys(const std::vector<CommandRun>& runs) {
  if (runs.empty()) return;
  std::vector<RunSite> sites;
  for (const auto& r : runs) sites.push_back(run_site(r));
  // The command's keys: the union over its runs (a sweep's grid points set the same keys).
  std::set<std::string> checked;
  for (const auto& r : runs)
    for (const auto& [key, where] : r.params.set_by_command) {
      if (!checked.insert(key).second) continue;
      const std::string why = scope_refusal(key, field(key).scope, sites);
      if (!why.empty()) throw Error(where + ": " + why);
    }
  // The files' keys, once per scene (a sweep may vary the scene's keys, never its builder).
  const Params& p = runs.front().params;
  const RunSite scene = scene_site(p);
  for (const auto& [key, where] : p.set_in_file) {
    if (p.set_by_command.count(key)) continue;  // replaced by the command's value: checked above
    const std::string why = scope_refusal(key, field(key).scope, {scene});
    if (!why.empty()) throw Error(where + ": " + why);
  }
}

}  // namespace xb
