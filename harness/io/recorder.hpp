// The HDF5 recorder. One group per run under /runs, its scalars as attributes and its
// per-iteration arrays as 1-D datasets; the schema is in results/README.md.
//
// A run is written completely or not at all: every append reads FILE into memory, adds the runs
// there, writes the new file to FILE.tmp, flushes it to disk and renames it over FILE (rename is
// atomic), so an interrupt (Ctrl-C, SIGKILL, power loss) or a full disk leaves the previous
// complete file (atomic_file.hpp; a failed write throws WriteError naming FILE and the cause).
#pragma once

#include "record.hpp"

#include <string>
#include <vector>

namespace xb {

// Appends `runs` to `path` atomically. fresh = true starts a new file (replacing an old one
// only when the new one is complete).
void append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh = false);

// Reads every run (attributes; datasets too if with_datasets). Throws xb::Error for a file
// that is missing, not HDF5 or without the group /runs. A run that cannot be read (not a group,
// a dangling link, an attribute that is an array or of another type, ...) throws too, unless
// `skipped` is given: then it is left out and its error ("FILE: ... run NAME ...") appended there.
std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets = false,
                                 std::vector<std::string>* skipped = nullptr);

// The number of runs in a file (0 if it does not exist).
int count_runs(const std::string& path);

}  // namespace xb
