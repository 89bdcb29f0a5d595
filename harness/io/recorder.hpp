// The HDF5 recorder. One group per run under /runs, its scalars as attributes and its
// per-iteration arrays as 1-D datasets; the schema is in results/README.md.
//
// One results file, many writers (results/README.md, docs/failures.md). FILE.h5 is a small index:
// /runs/<NNNN_name> are HDF5 external links to one file per run in the folder FILE.h5.runs/
// (FILE.h5.runs/<NNNN_name>.<random>.h5, itself a results file holding that one run), which every
// HDF5 reader (report, xpbd_bench.read, h5py, the plots) follows as if the groups were in FILE.h5.
// An append, under an exclusive lock (FILE.h5.runs/lock, file_lock.hpp), writes the new runs' files
// and then a new index, each through its own temporary file renamed into place (atomic_file.hpp):
// it costs the runs it adds and the index (a few hundred bytes a run), not the runs already there;
// an interrupt at any moment (Ctrl-C, SIGKILL, power loss) or a full disk leaves the previous
// index and every run it links; what a killed writer left (temporary files, run files no index
// links) is removed by the next writer, under the lock. A file of inline groups (written by
// `pack`, or before this layout) is read as it is; the first append moves its runs to run files.
#pragma once

#include "record.hpp"
#include "results_index.hpp"

#include <string>
#include <vector>

namespace xb {

// Adds runs to one results file, each run numbered after those the file holds when it is added
// (under the lock, so that concurrent writers never take the same name): a run's `name` is what
// follows the number, e.g. "cloth_hang_mgpbd" becomes "0004_cloth_hang_mgpbd".
class ResultsWriter {
 public:
  // replace = false: every add appends (the file is made when absent; sweep, run --append).
  // replace = true (run and solve --out): the first add starts a new file in place of the old
  // one; later adds append to it, unless another writer has replaced it since: then they throw
  // xb::Error saying so, and the file stays that writer's.
  ResultsWriter(std::string path, bool replace);
  // Writes the runs; returns their names in the file. Throws WriteError naming the file (a full
  // disk: the file as it was), or xb::Error (a file that is not a results file; a run holding a
  // name the schema does not list, before anything is written).
  std::vector<std::string> add(const std::vector<RunRecord>& runs);
  // The runs the file held after this writer's last add (0 before the first).
  int runs_in_file() const { return held_; }

 private:
  std::string path_, id_;
  bool replace_, started_ = false;
  int held_ = 0;
};

// Appends `runs` (named as for ResultsWriter::add) to `path`; fresh = true starts a new file.
// Returns their names in the file.
std::vector<std::string> append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh = false);

// Reads every run (attributes; datasets too if with_datasets), under a shared lock (no writer
// changes the file meanwhile). Throws xb::Error for a file that is missing, not HDF5 or without
// the group /runs. A run that cannot be read (not a group, a dangling link, an attribute that is
// an array or of another type, ...) throws too, unless `skipped` is given: then it is left out
// and its error ("FILE: ... run NAME ...") appended there.
std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets = false,
                                 std::vector<std::string>* skipped = nullptr);

// The number of runs in a file (0 if it does not exist).
int count_runs(const std::string& path);

// Writes every run of `src` into one self-contained file `dst` (the runs as groups, no links, no
// folder beside it): the file to hand to someone else. Replaces dst atomically. Runs that cannot be
// read are left out: returns their errors. Throws WriteError naming dst, or xb::Error naming src.
std::vector<std::string> pack_runs(const std::string& src, const std::string& dst);

}  // namespace xb
