// What the performance tracking shares between the deterministic-metrics tool
// (harness/perf/metrics.cpp) and the microbenchmarks (bench/microbench.cpp): the fixed set of
// captured systems and scenes, and how a system is captured.
#pragma once

#include "../params.hpp"
#include "../../core/sparse.hpp"
#include "../io/system_io.hpp"

#include <string>
#include <vector>

namespace xb::perf {

// A scene at one resolution, with the overrides that make it.
struct SceneCase {
  std::string label;               // "cloth_hang/r16": used in metric and benchmark names
  std::string scene;               // built-in scene name
  std::vector<std::string> sets;   // key=value overrides (resolution, frames, ...)
};

// A captured system with the label metrics and benchmarks are named by.
struct LabelledSystem : CapturedSystem {
  std::string label;
};

// xb::capture_system (harness/sim/capture.hpp) on a case, substep 0; p.max_iterations is raised to
// reach the iteration.
LabelledSystem capture_case(const SceneCase& c, int frame, int iteration, const std::vector<std::string>& extra_sets,
                            const std::string& driver = "cholmod");

// Resolved parameters of a case (defaults ← scene spec ← case overrides ← extra overrides).
Params case_params(const SceneCase& c, const std::vector<std::string>& extra_sets);

// Names of the registered linear solvers (global methods) that are built in, in registry order.
std::vector<std::string> available_linear_solvers();
// Names of the registered local methods.
std::vector<std::string> local_methods();
// Registered methods that are not available in this build (for the gate: their metrics are
// skipped rather than missing).
std::vector<std::string> unavailable_methods();

}  // namespace xb::perf
