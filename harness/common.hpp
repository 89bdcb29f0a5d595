// What the sub-commands share: parameters from scene + overrides, method lists, run records.
#pragma once

#include "../problems/params.hpp"
#include "recorder.hpp"
#include "stepper.hpp"

#include <string>
#include <vector>

namespace xb {

// defaults ← the scene spec ← the profile (harness/profile.hpp; "" = none) ← --set key=value
// overrides (in order), then validate().
Params resolve_params(const std::string& scene_name_or_file, const std::vector<std::string>& sets,
                      const std::string& profile = "");
// "key=value" → set_param (where = "--set").
void apply_set(Params& p, const std::string& key_value);

// A comma-separated list of method names, each known and available; throws listing valid ones.
// linear_only rejects the local methods.
std::vector<std::string> parse_methods(const std::string& list, bool linear_only = false);

// Provenance and the whole parameter set, as attributes of a run.
void add_provenance(RunRecord& r, const Params& p);
// A simulation run as a record: status and summary attributes, per-iteration datasets.
RunRecord make_simulation_record(const std::string& name, const Params& p, const std::string& method,
                                 const RunResult& res);
// "0003_cloth_hang_xpbd-gs": index within the file, then what ran.
std::string run_name(int index, const std::string& scene, const std::string& solver);

// One run of `run` or `solve`: a method and the form of its linear step.
struct MethodRun {
  std::string method;
  std::string form;  // dual | primal | auto for a global method ("" = the parameters' form); "" for a local one
  std::string tag;   // for the run's name: the method, with "_<form>" when several forms were asked for
};
// The runs of --solver × --form: a local method runs once, a global method once per form of
// `form_list` (comma-separated dual | primal | auto; empty = the parameters' form only).
std::vector<MethodRun> method_runs(const std::vector<std::string>& methods, const std::string& form_list);

// A run attribute as short text for tables ("-" if absent, numbers with 3 digits).
std::string attr_cell(const RunRecord& r, const std::string& key);

// Prints a report of a results file: "table" or "json".
void print_report(const std::string& path, const std::string& format);

}  // namespace xb
