// The results schema: every attribute and dataset a run group may hold, with its level and type.
// It is the one list the writers follow — append_runs refuses a run holding a name that is not
// here, or not of its type — and the one `report` and plots/ read: `xpbd-bench schema` prints it as
// JSON and results/schema.json (what plots/xbruns.py loads) is that output, checked by a test.
// results/README.md documents every name (checked by the same test). Parameter keys are
// attributes of every run as well (harness/params.hpp).
#pragma once

#include "record.hpp"

#include <string>
#include <vector>

namespace xb {

struct SchemaName {
  std::string name;   // a '/' in a dataset name is a subgroup
  std::string level;  // simulation | linear | any
  std::string type;   // int | float | number (int or float) | string; datasets: of their entries
};
struct ResultsSchema {
  std::vector<SchemaName> attributes, datasets;
};
const ResultsSchema& results_schema();

// Throws std::logic_error naming the first attribute or dataset of r that the schema does not
// list for r's level (a writer that drifted from the schema is a bug, not bad input).
void check_against_schema(const RunRecord& r);

// The schema and the parameter keys as JSON.
std::string schema_json();

}  // namespace xb
