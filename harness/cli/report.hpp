// `report`: a results file as a table or JSON, with runs timed under load marked.
#pragma once

#include "../io/recorder.hpp"

#include <string>

namespace xb {

// A run attribute as short text for tables ("-" if absent, numbers with 3 digits).
std::string attr_cell(const RunRecord& r, const std::string& key);

// Prints a report of a results file: "table" or "json".
void print_report(const std::string& path, const std::string& format);

}  // namespace xb
