// `report`: a results file as a table or JSON, with runs timed under load marked.
#pragma once

#include "../io/recorder.hpp"

#include <string>
#include <vector>

namespace xb {

// A run attribute as short text for tables ("-" if absent, numbers with 3 digits).
std::string attr_cell(const RunRecord& r, const std::string& key);

// Prints a report of a results file: "table" or "json". A run that cannot be read is named on
// stderr and left out; returns how many were.
int print_report(const std::string& path, const std::string& format);
// The same report of runs in hand (run and solve: the runs they added, not the whole file).
void print_runs(const std::vector<RunRecord>& runs, const std::string& format);
// What `repair` found and did, on stdout.
void print_repair(const std::string& path, const RepairReport& rep);
// Each unreadable run's error on stderr ("<command>: skipped: ..."), after the runs that were read.
void warn_skipped(const std::string& command, const std::vector<std::string>& skipped);

}  // namespace xb
