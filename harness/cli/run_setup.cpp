#include "run_setup.hpp"

#include "args.hpp"
#include "profile.hpp"

#include "../../core/error.hpp"
#include "../../core/process_memory.hpp"
#include "../../problems/primal_system.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/mpi/distributed.hpp"
#include "../../solvers/linear_solver.hpp"

#include <sstream>

namespace xb {

Params resolve_params(const std::string& scene, const std::vector<std::string>& sets, const std::string& profile) {
  Params p;
  load_scene_file(resolve_scene(scene), p);
  if (!profile.empty()) apply_profile(profile, p);
  for (const auto& kv : sets) apply_set(p, kv);
  validate(p);
  return p;
}

double time_budget_flag(const Args& args, const std::string& command) {
  const double s = args.get_double("--time-budget", default_time_budget);
  if (s < 0) throw Error(command + ": --time-budget must be >= 0 (s; 0 = no limit)");
  return s;
}

double memory_limit_flag(const Args& args, const std::string& command) {
  const double gb = args.get_double("--memory-limit", 0);
  if (!(gb >= 0) || gb > 1e6) throw Error(command + ": --memory-limit must be in [0, 1e6] (GB; 0 = no limit)");
  if (gb == 0) return 0;
  set_data_limit(static_cast<long long>(gb * 1e9 * 1.05 + 256e6));
  return gb * 1e9;
}

void apply_set(Params& p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) throw Error("--set '" + kv + "': expected key=value");
  set_param(p, kv.substr(0, eq), kv.substr(eq + 1), "--set");
}

std::vector<std::string> parse_methods(const std::string& list, bool linear_only, bool any_under_mpi) {
  std::vector<std::string> names;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) names.push_back(item);
  if (names.empty()) throw Error("no solver given (--solver A,B,...)");
  for (const auto& n : names) {
    const MethodInfo* m = find_method(n);
    if (!m || (linear_only && m->local)) {
      std::string valid;
      for (const auto& x : methods())
        if (!(linear_only && x.local)) valid += (valid.empty() ? "" : ", ") + x.name;
      throw Error("unknown solver '" + n + "' (valid: " + valid + ")");
    }
    if (!m->available) throw Error("solver '" + n + "' is not available: " + m->reason);
    if (mpi_size() > 1 && !any_under_mpi && !method_is_distributed(n))
      throw Error("solver '" + n + "' cannot run distributed (this is an MPI run with " + std::to_string(mpi_size()) +
                  " processes; only hypre and muelu can): run it without mpirun");
  }
  return names;
}

std::vector<MethodRun> method_runs(const std::vector<std::string>& methods, const std::string& form_list) {
  std::vector<std::string> forms;
  std::stringstream ss(form_list);
  for (std::string f; std::getline(ss, f, ',');) {
    check_form(f, "--form");
    forms.push_back(f);
  }
  if (forms.empty()) forms.push_back("");
  std::vector<MethodRun> runs;
  for (const auto& m : methods) {
    if (find_method(m)->local) {
      runs.push_back({m, "", m});
      continue;
    }
    for (const auto& f : forms) runs.push_back({m, f, forms.size() > 1 ? m + "_" + f : m});
  }
  return runs;
}

}  // namespace xb
