// Runs as records of a results file: provenance and every parameter as attributes, a simulation
// run's summary and per-iteration datasets (the schema is results/README.md), and run names.
#pragma once

#include "recorder.hpp"
#include "run_result.hpp"

#include "../params.hpp"

#include <string>

namespace xb {

// Provenance and the whole parameter set, as attributes of a run.
void add_provenance(RunRecord& r, const Params& p);
// A simulation run as a record: status and summary attributes, per-iteration datasets.
RunRecord make_simulation_record(const std::string& name, const Params& p, const std::string& method,
                                 const RunResult& res);
// "0003_cloth_hang_xpbd-gs": index within the file, then what ran.
std::string run_name(int index, const std::string& scene, const std::string& solver);

}  // namespace xb
