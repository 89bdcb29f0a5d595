// The HDF5 recorder. One group per run under /runs, its scalars as attributes and its
// per-iteration arrays as 1-D datasets; the schema is in results/README.md.
//
// A results file FILE.h5 is a store of run files and an index (results/README.md, docs/failures.md):
// each run is a file of its own in FILE.h5.runs/<store>/ (run_store.hpp), and what that folder
// holds is what the file holds; FILE.h5 is an index whose /runs/<name> are HDF5 external links to
// those files (results_index.hpp), which h5py and every HDF5 reader follow. An append, under an
// exclusive lock (FILE.h5.runs/lock, file_lock.hpp), writes the new run's file and links it into
// the store under the next number (link(2): never over another file), so it costs the run it adds
// and a listing of the folder's names, not the runs already there; the index is rewritten (a copy
// of the one before with the new links added, renamed into place) after a writer's first run,
// whenever the time since its last rewrite is ten times what that took, and at the end of every
// command. Readers take no lock and do not read the links: they list the store, so a file renamed
// with its folder, copied, or reached through a symbolic link reads the same from any working
// directory. A killed writer leaves every run it linked; what else it left (temporary files, an
// index behind the store, a store never switched to) is put right by the next writer or `repair`
// (store_upkeep.hpp). A file of inline groups (`pack`'s) or of the earlier layout is read as it is;
// its first writer moves it into a store.
#pragma once

#include "record.hpp"
#include "store_upkeep.hpp"

#include <chrono>
#include <string>
#include <vector>

namespace xb {

// Adds runs to one results file, each numbered after the runs the file holds when it is added
// (under the lock: concurrent writers never take one name): a run's `name` is what follows the
// number, e.g. "cloth_hang_mgpbd" becomes "0004_cloth_hang_mgpbd". A run with a `sweep_key` that
// the file holds already (another writer ran the same job meanwhile) is not added again.
class ResultsWriter {
 public:
  // replace = false: every add appends (the file is made when absent; sweep, run --append).
  // replace = true (run and solve --out): the first add starts a new file in place of the old
  // one; later adds append to it, unless another writer has replaced it since: then they throw
  // xb::Error saying so, and the file stays that writer's. A symbolic link `path` is followed once,
  // here: the file it points to is written, the link stays.
  ResultsWriter(std::string path, bool replace);
  ~ResultsWriter();  // close(), its errors left unsaid
  ResultsWriter(ResultsWriter&& o) noexcept;
  ResultsWriter(const ResultsWriter&) = delete;
  ResultsWriter& operator=(const ResultsWriter&) = delete;
  ResultsWriter& operator=(ResultsWriter&&) = delete;
  // Writes the runs; returns their names in the file (a job the file held already: that run's
  // name). Throws WriteError naming the file (a full disk: the file as it was), or xb::Error (a
  // file that is not a results file; a run holding a name the schema does not list, before
  // anything is written; a file system whose locks do not lock).
  std::vector<std::string> add(const std::vector<RunRecord>& runs);
  // Brings the index up to date with the runs this writer added (every command ends with it).
  // Throws WriteError naming the file.
  void close();
  // The runs the file held after this writer's last add (0 before the first).
  int runs_in_file() const { return held_; }
  // The runs add() did not write because the file held their job already.
  int jobs_held_already() const { return duplicates_; }

 private:
  struct Target;
  Target open_target(Upkeep& found);
  void write_index_now(const Target& t, bool whole);
  std::string shown_, path_, id_, store_;
  bool replace_, started_ = false, stale_ = false, cleaned_ = false, refreshed_ = false;
  int held_ = 0, duplicates_ = 0;
  double refresh_cost_ = 0;
  std::chrono::steady_clock::time_point refreshed_at_{};
};

// Appends `runs` (named as for ResultsWriter::add) to `path`; fresh = true starts a new file.
// Returns their names in the file.
std::vector<std::string> append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh = false);

// Reads every run (attributes; datasets too if with_datasets), by name; no lock: what the store
// holds as it is listed. Throws xb::Error for a file that is missing, not HDF5 or without the group
// /runs. A run that cannot be read (a dangling link, a run file gone or damaged, an attribute that
// is an array or of another type, ...) throws too, unless `skipped` is given: then it is left out
// and its error ("FILE: ... run NAME ...") appended there.
std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets = false,
                                 std::vector<std::string>* skipped = nullptr);

// The number of runs in a file (0 if it does not exist), from its store's listing (no run file
// opened) or its index.
int count_runs(const std::string& path);

// Writes every run of `src` into one self-contained file `dst` (the runs as groups, no links, no
// folder beside it): the file to hand to someone else. Replaces dst atomically. Runs that cannot be
// read are left out: returns their errors. Throws WriteError naming dst, or xb::Error naming src.
std::vector<std::string> pack_runs(const std::string& src, const std::string& dst);

}  // namespace xb
