// The runs of a results file FILE.h5 (recorder.hpp): one file per run in the store folder
// FILE.h5.runs/<store>/ (<store>: 8 hex digits, which the index FILE.h5 names in its attribute
// `store`). What that folder holds is what the file holds: a run is added by giving its complete,
// flushed file its name there with link(2), which never replaces a file, and nothing else; readers
// list the folder and need no lock. A run file is named NNNN_<name>[.k<key>].h5: its group name
// /runs/NNNN_<name> (characters other than letters, digits and _+:=,@- as %XX) and, for a sweep's
// run, 16 hex digits of its sweep_key, so that listing the folder (no file opened) gives every
// run's number, name and job. The folder also holds the lock (FILE.h5.runs/lock) and a sweep's job
// counters (queue-*).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <hdf5.h>

namespace xb {

// FILE.runs: the folder of a results file's stores, lock and counters.
std::string runs_folder(const std::string& path);
// FILE.runs/lock: the lock of a results file's writers (file_lock.hpp).
std::string results_lock_path(const std::string& path);
// FILE.runs/<store>: the folder of a store's run files.
std::string store_folder(const std::string& path, const std::string& store);
// Whether a name in FILE.runs/ is a store's: 8 hex digits.
bool is_store_name(const std::string& name);
// 8 random hex digits: the name of a new store.
std::string new_store_name();

// The file a results path names, its symbolic links followed once (a link to a file not made yet:
// where it points), so that a symlinked --out writes the target and the folder beside it and never
// replaces the link. Any other path as given.
std::string resolve_results_path(const std::string& path);

// One run file of a store, as its name tells.
struct StoredRun {
  long long number = 0;  // its NNNN (0 when the name has none)
  std::string name;      // its group name: /runs/<name> in the run file and in the index
  std::string file;      // the file's name in the store folder
  std::string key;       // 16 hex digits of its sweep_key ("" for a run without one)
};
// "NNNN_<name>[.k<key>].h5" for a group name and a key digest ("" for none).
std::string run_file_name(const std::string& name, const std::string& key);
// The run a file name describes; false for any other name (a temporary file, a counter).
bool parse_run_file(const std::string& file, StoredRun& out);
// 16 hex digits (FNV-1a, 64 bits) of a sweep_key: a job's name in a run file's name.
std::string key_digest(const std::string& sweep_key);
// "NNNN_name": a run's group name from its number (at least 4 digits).
std::string numbered(long long number, const std::string& name);

// A store folder as listed (names only: no file is opened).
struct StoreListing {
  bool exists = false;
  std::vector<StoredRun> runs;           // by number, then name
  std::vector<std::string> temporaries;  // paths of temporary files (.NAME.<...>.tmp) in it
  long long last = 0;                    // the largest run number
};
StoreListing list_store(const std::string& folder);

// A run file's bytes: a results file holding the root attributes and what `fill` adds (the group
// /runs/<name>), built in memory (h5io.hpp).
std::vector<char> run_file_image(const std::function<void(hid_t)>& fill);
// Writes `image` into the store folder as the new file `file` (a temporary file, flushed, then
// linked: TmpFile::commit_new). Returns false, writing nothing, when a file of that name exists.
// Throws WriteError naming `shown` (the results file).
bool commit_run_file(const std::string& folder, const std::string& file, const std::vector<char>& image,
                     const std::string& shown);

}  // namespace xb
