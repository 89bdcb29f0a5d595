// The parts of a results file (recorder.hpp) as an append builds them: the index FILE (root
// attributes, /runs/<name> external links) in memory, and one file per run in FILE.runs/.
// Everything here runs under FILE's exclusive lock and the HDF5 Guard (recorder.cpp).
#pragma once

#include "h5handle.hpp"
#include "record.hpp"

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace xb {

// FILE.runs: the folder of a results file's runs (and of its lock).
std::string runs_folder(const std::string& path);
// FILE.runs/lock: the lock file of a results file (file_lock.hpp).
std::string results_lock_path(const std::string& path);

// An index being built, in memory.
struct Index {
  h5::H file{H5I_INVALID_HID, nullptr}, runs{H5I_INVALID_HID, nullptr};  // the file and its /runs
  std::string writer;              // the attribute `writer`: who started the file
  std::vector<std::string> names;  // the links under /runs
  std::set<std::string> linked;    // the run files they link, as names in FILE.runs/
};

// The run files an append writes, FILE.runs/<name>.<8 hex>.h5: removed again when the append
// fails (the destructor), unless keep() was called once the index linking them was in place.
class RunFiles {
 public:
  explicit RunFiles(std::string path) : path_(std::move(path)) {}
  ~RunFiles();
  RunFiles(const RunFiles&) = delete;
  RunFiles& operator=(const RunFiles&) = delete;
  // Writes one run file, a results file of its own: the root attributes and what `fill` adds to
  // the file in memory (the group /runs/<name>). Returns its name relative to FILE's folder, as the
  // index links it. Throws WriteError naming FILE.
  std::string write(const std::string& name, const std::function<void(hid_t)>& fill);
  void keep() { files_.clear(); }

 private:
  std::string path_;
  std::vector<std::string> files_;
};

// A new, empty index started by `writer`.
Index new_index(const std::string& writer);
// A new index holding every root attribute and link of the file at `path`: external links as they
// are, runs stored inline (a packed or older file) written out as run files through `made`.
// Throws xb::Error for a file that is not a results file.
Index carry_index(const std::string& path, RunFiles& made);
// The number the next run takes: one more than the largest NNNN of "NNNN_..." and than the count.
int next_run_number(const Index& index);
// /runs/<name> → `file` (relative to FILE's folder), object /runs/<name>.
void link_run(Index& index, const std::string& name, const std::string& file);
// The group /runs/<name> of a run in `file`. Throws xb::Error for a name it already holds.
void write_run(hid_t file, const RunRecord& r, const std::string& name);
// Writes the index as FILE, atomically. Throws WriteError naming FILE.
void commit_index(const std::string& path, const Index& index);
// Removes what no writer uses (the caller holds the lock): temporary files of FILE and in
// FILE.runs/; when FILE was `replaced` (run --out, pack), also the run files that neither `index`
// nor another results file in FILE's folder links (the replaced file's, or left by a killed writer).
void collect_garbage(const std::string& path, const Index& index, bool replaced);
// One self-contained file (every run a group, copied through its link) holding the runs of `src`;
// runs that cannot be read are left out and named in `skipped`. Throws xb::Error naming src.
std::vector<char> packed_image(const std::string& src, std::vector<std::string>& skipped);

}  // namespace xb
