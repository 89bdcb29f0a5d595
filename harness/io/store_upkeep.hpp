// Keeping a results file whole (recorder.hpp): what its writers do besides adding runs — move an
// older file into a store, adopt a store whose index is gone, remove what no reader needs — and
// `repair`, which does all of that and rebuilds the index from the run files. Everything here runs
// under FILE's exclusive lock (file_lock.hpp) and the HDF5 Guard; FILE is a resolved path
// (run_store.hpp).
#pragma once

#include "results_index.hpp"
#include "run_store.hpp"

#include <string>
#include <vector>

namespace xb {

// What the upkeep found and did.
struct Upkeep {
  std::vector<std::string> relinked;  // runs that no index listed, now in the store and the index
  std::vector<std::string> dangling;  // runs an index listed that are gone or unreadable (left out)
  std::vector<std::string> removed;   // temporary files, stores that are not the file's, older files moved
  std::vector<std::string> notes;     // anything else (a store adopted)
};

// Copies the runs of an older file (its inline groups, the run files its links of the earlier
// layout name, and run files of that layout in FILE.runs/ that no link names: a writer killed
// between its run file and its index) into the new store `store`, each under its name (a name taken
// already: the next number). The older files stay until the index names the store
// (collect_garbage removes them then). Returns the store's listing. Throws WriteError naming FILE.
StoreListing move_into_store(const std::string& path, const IndexHead& head, const std::string& store, Upkeep& found);

// The store of FILE.runs/ with the most run files, other than `except` ("" when there is none): the
// one to adopt when FILE's index is gone or names a folder that is gone. Says so in `found`.
std::string store_to_adopt(const std::string& path, const std::string& except, Upkeep& found);

// Removes what no reader needs: temporary files of FILE and in FILE.runs/ and its store, stores
// other than `store` (a replaced file's, or a write that never got its index), counters of sweeps
// that are gone, and, once FILE has a store, run files of the earlier layout (moved into it).
void collect_garbage(const std::string& path, const std::string& store, const StoreListing& listing, Upkeep& found);

// The runs FILE's index lists that `listing` (its store, as listed now) does not hold; with
// `unindexed`, the runs the store holds that the index does not list are added there.
std::vector<std::string> unlisted_runs(const std::string& path, const StoreListing& listing,
                                       std::vector<std::string>* unindexed = nullptr);

// `repair FILE`: under FILE's lock, the store found (or adopted, or an older file moved into a new
// one), the index rebuilt whole from its run files, what no reader needs removed. `shown` is the
// path as the user gave it.
struct RepairReport {
  int runs = 0;
  bool packed = false;  // FILE holds its runs inline (pack's): nothing to rebuild
  Upkeep found;
};
RepairReport repair_results(const std::string& shown);

// The lines a writer says about what it found (relinked, dangling, notes), "FILE: ..." each.
std::vector<std::string> upkeep_lines(const std::string& shown, const Upkeep& found);

}  // namespace xb
