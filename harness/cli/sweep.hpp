// Sweep specs: a base scene, solvers, fixed overrides and a grid of any parameter key, expanded
// into one job per (grid point × solver × repeat). Each job carries a canonical key so that a
// rerun of the same sweep into the same file skips what is already there (harness/cli/cmd_sweep.cpp).
//
//   scene = "bar_hang"                  # built-in name or a .toml path (relative to the spec)
//   solvers = ["mgpbd", "cholmod"]
//   frames = 1                          # optional, as --frames
//   repeats = 1                         # optional, runs per grid point and solver
//   time_budget = 3600                  # optional, s per run (0 = none; default 3600)
//   reference = false                   # optional, per-substep reference + position_error
//   description = "..."                 # optional, free text
//   profile = "authors"                 # optional, as run --profile (sweep --profile replaces it)
//   [set]                               # fixed overrides, as with --set
//   max_iterations = 50
//   [grid]                              # the cartesian product of these lists
//   "amg.strength_threshold" = [0.0, 0.1, 0.25]
//   [sizes.paper]                       # optional: what changes at another size (sweep --size paper)
//   time_budget = 600                   #   any key above; set.KEY / grid.KEY entries replace or add
//   grid.resolution = [16, 32, 64]      #   to those of [set] / [grid]
#pragma once

#include "run_setup.hpp"

#include "../params.hpp"

#include <string>
#include <utility>
#include <vector>

namespace xb {

struct SweepSpec {
  std::string path;                    // the spec file
  std::string size = "default";        // the [sizes.NAME] table applied
  std::string scene;                   // resolved scene file
  std::vector<std::string> solvers;
  int repeats = 1;
  double time_budget = default_time_budget;
  bool reference = false;
  std::string description;
  std::string profile;                 // "" = none; applied after the scene, before [set] and [grid]
  std::vector<std::string> sets;       // "key=value", in order (frames first if given)
  // Grid axes in spec order: key and its values (as written; canonicalised in the jobs).
  std::vector<std::pair<std::string, std::vector<std::string>>> grid;
};

struct SweepJob {
  int index = 0;                       // position in the sweep, 0-based
  Params params;                       // fully resolved
  std::string solver;
  int repeat = 0;
  int point = 0;                       // grid point (same for all solvers and repeats)
  std::vector<std::pair<std::string, std::string>> values;  // swept key → canonical value
  std::string point_text;              // "amg.strength_threshold=0.1 resolution=4" ("-" if no grid)
  std::string key;                     // base hash | point | solver | repeat: unique per job
};

// Reads and validates the whole spec at one size: unknown keys, bad values, unknown or
// unavailable solvers, empty lists, duplicate grid values, an unknown size. Throws xb::Error with
// one line naming file:line and key.
// `profile` (sweep --profile; "" = the spec's own) replaces the spec's profile.
SweepSpec parse_sweep_spec(const std::string& path, const std::string& size = "default",
                           const std::string& profile = "");

// All jobs, grid point major, then solver, then repeat. Every job's Params are resolved and
// validated here, so a bad combination fails before anything runs.
std::vector<SweepJob> expand_sweep(const SweepSpec& spec);

// A hash (hex) of what a sweep's runs share: the scene file's text, the profile file's text, the
// fixed overrides ([set], frames; values canonical) and the reference flag. Runs of one sweep carry it as `sweep_base`.
std::string sweep_base_hash(const SweepSpec& spec);

// A parameter value as short canonical text (doubles as %.15g).
std::string canonical_value(const Params& p, const std::string& key);

}  // namespace xb
