// The writer of results files (recorder.hpp); the readers are in results_reader.cpp.
#include "recorder.hpp"
#include "schema.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <filesystem>
#include <iostream>
#include <utility>

namespace fs = std::filesystem;

namespace xb {

namespace {

using namespace h5;

struct Silence {  // HDF5 prints error stacks by default; we report our own messages.
  Silence() { silence_errors(); }
};
const Silence silence_hdf5;

// "<pid>@<host>:<random>": who started a file (its attribute `writer`).
std::string new_writer_id() { return writer_tag() + ":" + random_hex8(); }

// "pid 123 on host" from a writer id, for messages.
std::string writer_words(const std::string& id) {
  const size_t at = id.find('@'), colon = id.rfind(':');
  if (at == std::string::npos || colon == std::string::npos || colon < at) return "'" + id + "'";
  return "pid " + id.substr(0, at) + " on " + id.substr(at + 1, colon - at - 1);
}

// The group /runs/<name> of a run in `file`.
void write_run(hid_t file, const RunRecord& r, const std::string& name) {
  H lcpl = link_create_plist();
  const std::string path = "/runs/" + name;
  H g(H5Gcreate2(file, path.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(g, "create group " + path);
  for (const auto& [k, v] : r.attrs) write_attr(g, k, v);
  for (const auto& [k, v] : r.datasets) write_dataset(g, k, v);
}

std::string sweep_key_of(const RunRecord& r) {
  auto it = r.attrs.find("sweep_key");
  const auto* s = it == r.attrs.end() ? nullptr : std::get_if<std::string>(&it->second);
  return s ? *s : "";
}

// The run of the store that did the job `key` already ("" if none): its file name says the job's
// digest, its attribute the job itself.
std::string held_job(const std::string& folder, const StoreListing& listing, const std::string& key) {
  const std::string digest = key_digest(key);
  for (const auto& r : listing.runs) {
    if (r.key != digest) continue;
    try {
      H f = open_file(folder + "/" + r.file);
      H g = open_group(f, "/runs/" + r.name, r.file);
      const auto attrs = read_attrs(g, r.file);
      auto it = attrs.find("sweep_key");
      if (it != attrs.end() && std::get_if<std::string>(&it->second) && std::get<std::string>(it->second) == key) return r.name;
    } catch (const Error&) {  // a damaged file holds no job: the job is run again
    }
  }
  return "";
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

// Where an add goes: the index as it is, the store and its listing; `start`: the index must be
// written whole to name this store (a new file, a replaced one, an older file moved into a store).
struct ResultsWriter::Target {
  IndexHead head;
  std::string store, folder;
  StoreListing listing;
  bool start = false, created = false;  // created: the store folder is this add's (removed if it fails)
};

ResultsWriter::ResultsWriter(std::string path, bool replace)
    : shown_(std::move(path)), path_(resolve_results_path(shown_)), id_(new_writer_id()), replace_(replace) {}

ResultsWriter::~ResultsWriter() {
  try {
    close();
  } catch (...) {  // the runs are in the store; the next writer or repair brings the index up to date
  }
}

ResultsWriter::ResultsWriter(ResultsWriter&& o) noexcept
    : shown_(std::move(o.shown_)), path_(std::move(o.path_)), id_(std::move(o.id_)), store_(std::move(o.store_)),
      replace_(o.replace_), started_(o.started_), stale_(std::exchange(o.stale_, false)), cleaned_(o.cleaned_),
      refreshed_(o.refreshed_), held_(o.held_), duplicates_(o.duplicates_), refresh_cost_(o.refresh_cost_),
      refreshed_at_(o.refreshed_at_) {}

ResultsWriter::Target ResultsWriter::open_target(Upkeep& found) {
  Target t;
  t.head = read_index_head(path_);
  using K = IndexHead::Kind;
  std::error_code ec;
  if (replace_ && started_ && (t.head.kind != K::store || t.head.store != store_))
    throw Error(shown_ + " was replaced by another writer (" + writer_words(t.head.writer) +
                ") after this command's first run; the file is that writer's now");
  const bool fresh = replace_ && !started_;
  if (!fresh && t.head.kind == K::store && fs::is_directory(store_folder(path_, t.head.store), ec)) {
    t.store = t.head.store;
  } else if (!fresh && t.head.kind != K::older) {  // no index, or one whose store is gone: adopt a store
    t.store = store_to_adopt(path_, "", found);
    if (t.store.empty() && t.head.kind == K::store)
      throw Error(shown_ + ": its runs folder " + runs_folder(shown_) + "/" + t.head.store +
                  " is missing (moved, renamed or not copied with it?): put it back beside " + shown_ +
                  ", or write to another file");
    t.start = true;
  }
  if (t.store.empty()) {  // a new file, a replaced one, or an older file moved into a store
    t.store = new_store_name();
    t.start = t.created = true;
    if (!fresh) t.listing = move_into_store(path_, t.head, t.store, found);  // an older file's runs, run files of the earlier layout
  }
  t.folder = store_folder(path_, t.store);
  if (!t.start) t.listing = list_store(t.folder);
  else if (!t.listing.exists) {
    fs::create_directories(t.folder, ec);
    if (ec) throw WriteError(shown_, ec.value(), "cannot write " + shown_ + ": cannot create " + t.folder + ": " + errno_text(ec.value()));
    t.listing = list_store(t.folder);
  }
  if (t.start) {
    IndexHead head = new_index_head(t.store, fresh || t.head.writer.empty() ? id_ : t.head.writer);
    if (!fresh)
      for (const auto& [k, v] : t.head.attrs) head.attrs.emplace(k, v);
    t.head = std::move(head);
  }
  return t;
}

void ResultsWriter::write_index_now(const Target& t, bool whole) {
  const auto start = std::chrono::steady_clock::now();
  write_index(path_, t.head, t.listing.runs, whole);
  refresh_cost_ = seconds_since(start);
  refreshed_at_ = std::chrono::steady_clock::now();
  refreshed_ = true;
  stale_ = false;
}

std::vector<std::string> ResultsWriter::add(const std::vector<RunRecord>& runs) {
  for (const auto& r : runs) check_against_schema(r);  // before anything is written
  make_parent(path_);
  const FileLock lock(results_lock_path(path_), FileLock::Kind::exclusive, shown_);
  const Guard guard;  // after the file lock (h5handle.hpp)
  Upkeep found;
  Target t = open_target(found);
  std::vector<std::string> names, linked;
  try {
    for (const auto& r : runs) {
      const std::string key = sweep_key_of(r);
      if (const std::string held = key.empty() ? "" : held_job(t.folder, t.listing, key); !held.empty()) {
        names.push_back(held);  // claimed at commit: another writer ran this job meanwhile
        ++duplicates_;
        continue;
      }
      std::string base = r.name;
      for (char& c : base)
        if (c == '/') c = '_';
      const long long number = t.listing.last + 1;
      const std::string name = numbered(number, base), file = run_file_name(name, key.empty() ? "" : key_digest(key));
      const auto image = run_file_image([&](hid_t f) { write_run(f, r, name); });
      if (!commit_run_file(t.folder, file, image, shown_))
        throw Error("cannot write " + shown_ + ": " + t.folder + "/" + file +
                    " appeared while this writer held the file's lock: its file system's locks do not lock; write elsewhere");
      linked.push_back(t.folder + "/" + file);
      t.listing.runs.push_back({number, name, file, key.empty() ? "" : key_digest(key)});
      t.listing.last = number;
      names.push_back(name);
    }
    stale_ = stale_ || !linked.empty();
    if (t.start || (stale_ && (!refreshed_ || seconds_since(refreshed_at_) >= 10 * refresh_cost_))) write_index_now(t, t.start);
  } catch (...) {  // the file as it was: the runs of this add unlinked, a store it started removed
    std::error_code ec;
    for (const auto& f : linked) fs::remove(f, ec);
    if (t.created) fs::remove_all(t.folder, ec);
    throw;
  }
  if (t.start || !cleaned_) collect_garbage(path_, t.store, t.listing, found);
  cleaned_ = true;
  for (const auto& line : upkeep_lines(shown_, found)) std::cerr << "xpbd-bench: " << line << "\n";
  started_ = true;
  store_ = t.store;
  held_ = static_cast<int>(t.listing.runs.size());
  return names;
}

void ResultsWriter::close() {
  if (!stale_) return;
  const FileLock lock(results_lock_path(path_), FileLock::Kind::exclusive, shown_);
  const Guard guard;
  Target t;
  t.head = read_index_head(path_);
  stale_ = false;
  if (t.head.kind != IndexHead::Kind::store || t.head.store != store_) return;  // replaced meanwhile
  t.store = store_;
  t.listing = list_store(store_folder(path_, store_));
  write_index_now(t, false);
}

std::vector<std::string> append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh) {
  ResultsWriter w(path, fresh);
  auto names = w.add(runs);
  w.close();
  return names;
}

}  // namespace xb
