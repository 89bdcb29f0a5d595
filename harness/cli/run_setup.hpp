// What `run`, `solve`, `capture` and `sweep` share before anything runs: the parameters (defaults ←
// scene ← profile ← --set) and the method list (--solver × --form).
#pragma once

#include "../params.hpp"

#include <string>
#include <vector>

namespace xb {

class Args;

// The longest one run may take, in s, unless --time-budget says otherwise (0 = no limit): generous,
// but a run asked for 1e9 iterations or frames ends with status `over_budget` instead of never.
constexpr double default_time_budget = 3600;
// The parameter `frames` is at most this (problems/scene_settings.cpp), so frame numbers are below it.
constexpr int max_frames = 1000000000;
// --time-budget S of `command` (>= 0), or default_time_budget.
double time_budget_flag(const Args& args, const std::string& command);
// --memory-limit GB (10^9 bytes; 0 or absent = none) in bytes: the resident set a run may reach
// (status out_of_memory past it). Caps the process's data segment a little above it (RLIMIT_DATA:
// the limit, 5% and 256 MB more), so that one allocation past it fails inside the run instead of
// the system killing the process. Throws xb::Error for a bad value.
double memory_limit_flag(const Args& args, const std::string& command);

// defaults ← the scene spec ← the profile (cli/profile.hpp; "" = none) ← --set key=value
// overrides (in order), then validate().
Params resolve_params(const std::string& scene_name_or_file, const std::vector<std::string>& sets,
                      const std::string& profile = "");
// "key=value" → set_param (where = "--set").
void apply_set(Params& p, const std::string& key_value);

// A comma-separated list of method names, each known and available; throws listing valid ones.
// linear_only rejects the local methods. Under mpirun only the distributed methods (hypre, muelu)
// are accepted, unless any_under_mpi (a sweep, whose ranks may share its jobs: cmd_sweep.cpp).
std::vector<std::string> parse_methods(const std::string& list, bool linear_only = false, bool any_under_mpi = false);

// One run of `run` or `solve`: a method and the form of its linear step.
struct MethodRun {
  std::string method;
  std::string form;  // dual | primal | auto for a global method ("" = the parameters' form); "" for a local one
  std::string tag;   // for the run's name: the method, with "_<form>" when several forms were asked for
};
// The runs of --solver × --form: a local method runs once, a global method once per form of
// `form_list` (comma-separated dual | primal | auto; empty = the parameters' form only).
std::vector<MethodRun> method_runs(const std::vector<std::string>& methods, const std::string& form_list);

}  // namespace xb
