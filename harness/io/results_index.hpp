// The index of a results file (recorder.hpp): FILE.h5 itself, what h5py and every HDF5 tool open.
// Its root attributes (schema_version, generator, writer: who started the file; store: the folder
// FILE.h5.runs/<store>/ of its run files; links_to: the folder its links name; runs_indexed: the
// largest run number it links) and /runs/<name>, an HDF5 external link to each run's group in its
// run file. The run files are the truth (run_store.hpp); the index is rebuilt from them, replaced
// whole (a temporary file renamed over FILE), never modified in place, so a reader holds one
// complete version or the next. A file written before stores (its runs inline: `pack`'s, or older
// ones; or external links to FILE.h5.runs/<name>.<8 hex>.h5) has no `store`: read as it is and
// moved into a store by its first writer (store_upkeep.hpp).
#pragma once

#include "h5handle.hpp"
#include "record.hpp"
#include "run_store.hpp"

#include <map>
#include <string>
#include <vector>

namespace xb {

struct IndexHead {
  enum class Kind { absent, store, older };  // older: inline groups or links of the earlier layout
  Kind kind = Kind::absent;
  std::string store, writer, links_to;
  long long indexed = 0;                   // runs_indexed
  std::map<std::string, AttrValue> attrs;  // every root attribute
};

// The index's root attributes. absent when there is no file at `path` (a resolved path,
// run_store.hpp). Throws xb::Error for a file that is not HDF5 or has no group /runs.
IndexHead read_index_head(const std::string& path);
// A new index head for a store started by `writer`.
IndexHead new_index_head(const std::string& store, const std::string& writer);

// The folder of the index's store: FILE.runs/<store>, or where no such folder is (FILE renamed
// without it) the one its links name, relative to FILE's folder, when that one is there.
std::string store_folder_of(const std::string& path, const IndexHead& head);
// "r.h5.runs/<store>": the store folder as the index's links name it, relative to FILE's folder.
std::string links_prefix(const std::string& path, const std::string& store);

// Writes the index of `head`'s store for `runs` (its listing) as FILE, atomically, under FILE's lock.
// whole = false adds to the index on disk the runs numbered after head.indexed, copying the rest
// as it is (a copy of its bytes, no link rebuilt); it is built whole instead when the index on disk
// is not that store's, names the folder otherwise (FILE renamed), or cannot be read. Returns the
// largest run number the new index links. Throws WriteError naming FILE.
long long write_index(const std::string& path, const IndexHead& head, const std::vector<StoredRun>& runs, bool whole);

// A member of /runs in an index: a run group stored in it, an external link, or something else.
struct IndexMember {
  enum class Kind { group, external, other };
  std::string name;
  Kind kind = Kind::other;
  std::string file, object;  // an external link's target
};
// Every member of /runs, in name order (one pass: H5Literate). Throws xb::Error naming `where`.
std::vector<IndexMember> index_members(hid_t runs, const std::string& where);
// The file an external link of the index at `path` (resolved) names, as this project resolves it:
// "<x>.runs/<rest>" is `path`.runs/<rest> (the runs folder beside FILE, whatever FILE is called
// now); another relative name is relative to FILE's folder, never to the working directory.
std::string link_target(const std::string& path, const std::string& file);

}  // namespace xb
