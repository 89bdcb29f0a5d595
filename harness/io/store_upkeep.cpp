#include "store_upkeep.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>

namespace fs = std::filesystem;

namespace xb {

using namespace h5;

namespace {

// A run file of the earlier layout, in FILE.runs/ itself: <name>.<8 hex>.h5.
bool older_run_file(const std::string& name) {
  const size_t n = name.size();
  if (n < 13 || name[0] == '.' || !name.ends_with(".h5") || name[n - 12] != '.') return false;
  for (size_t i = n - 11; i < n - 3; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(name[i]))) return false;
  return true;
}

std::vector<fs::path> entries_of(const std::string& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) out.push_back(it->path());
  std::sort(out.begin(), out.end());
  return out;
}

std::string canonical(const std::string& p) {
  std::error_code ec;
  const fs::path c = fs::weakly_canonical(p, ec);
  return ec ? p : c.string();
}

// Copies runs into a store folder as new run files.
class StoreFiller {
 public:
  StoreFiller(std::string path, const std::string& store) : path_(std::move(path)), folder_(store_folder(path_, store)) {
    std::error_code ec;
    fs::create_directories(folder_, ec);
    if (ec) throw WriteError(path_, ec.value(), "cannot write " + path_ + ": cannot create " + folder_ + ": " + errno_text(ec.value()));
  }
  // The group `object` under `loc` as run `name` (a name taken: the next number). Returns the name.
  std::string copy(hid_t loc, const std::string& object, std::string name) {
    for (char& c : name)
      if (c == '/') c = '_';
    if (names_.count(name)) name = numbered(last_ + 1, name.substr(name.find('_') == std::string::npos ? 0 : name.find('_') + 1));
    std::string key;
    {
      H g(H5Oopen(loc, object.c_str(), H5P_DEFAULT), H5Oclose);
      if (g < 0) throw Error("cannot open " + object);
      if (H5Aexists(g, "sweep_key") > 0) {
        H a(H5Aopen(g, "sweep_key", H5P_DEFAULT), H5Aclose);
        const AttrValue v = read_attr(a, object + " attribute 'sweep_key'");
        if (const auto* s = std::get_if<std::string>(&v)) key = key_digest(*s);
      }
    }
    const std::vector<char> image = run_file_image([&](hid_t f) {
      H lcpl = link_create_plist();
      check(H5Ocopy(loc, object.c_str(), f, ("/runs/" + name).c_str(), H5P_DEFAULT, lcpl), "copy run " + name);
    });
    if (!commit_run_file(folder_, run_file_name(name, key), image, path_)) throw Error(path_ + ": two runs named " + name);
    StoredRun r;
    parse_run_file(run_file_name(name, key), r);
    names_.insert(name);
    last_ = std::max(last_, r.number);
    return name;
  }
  const std::set<std::string>& names() const { return names_; }

 private:
  std::string path_, folder_;
  std::set<std::string> names_;
  long long last_ = 0;
};

// The one run of a run file of the earlier layout, copied in. Returns its name in the store.
std::string copy_older_run_file(StoreFiller& fill, const std::string& file) {
  H f = open_file(file);
  H runs = open_group(f, "/runs", file);
  const auto members = index_members(runs, file + ": /runs");
  if (members.size() != 1 || link_kind(runs, members[0].name) != Kind::group) throw Error(file + ": not a run file (one run group)");
  return fill.copy(runs, members[0].name, members[0].name);
}

}  // namespace

StoreListing move_into_store(const std::string& path, const IndexHead& head, const std::string& store, Upkeep& found) {
  StoreFiller fill(path, store);
  std::set<std::string> linked;  // the files of the earlier layout the index links
  if (head.kind == IndexHead::Kind::older) {
    H f = open_file(path);
    H runs = open_group(f, "/runs", path);
    for (const auto& m : index_members(runs, path + ": /runs")) {
      try {
        if (m.kind == IndexMember::Kind::external) {
          const std::string target = link_target(path, m.file);
          linked.insert(canonical(target));
          H t = open_file(target);
          if (link_kind(t, m.object) != Kind::group) throw Error(target + ": " + m.object + " is not a run group");
          fill.copy(t, m.object, m.name);
        } else if (link_kind(runs, m.name) == Kind::group) {
          fill.copy(runs, m.name, m.name);
        } else {
          throw Error(std::string("is ") + kind_text(link_kind(runs, m.name)) + ", not a run group");
        }
      } catch (const WriteError&) {
        throw;
      } catch (const Error& e) {
        found.dangling.push_back(m.name + ": " + e.what());
      }
    }
  }
  for (const auto& p : entries_of(runs_folder(path))) {
    const std::string name = p.filename().string();
    if (!older_run_file(name) || linked.count(canonical(p.string()))) continue;
    try {
      found.relinked.push_back(copy_older_run_file(fill, p.string()) + " (from " + name + ", which no index listed)");
    } catch (const WriteError&) {
      throw;
    } catch (const Error& e) {
      found.dangling.push_back(name + ": " + e.what());
    }
  }
  return list_store(store_folder(path, store));
}

std::string store_to_adopt(const std::string& path, const std::string& except, Upkeep& found) {
  std::string best;
  size_t most = 0;
  std::vector<std::pair<std::string, size_t>> stores;
  std::error_code ec;
  for (const auto& p : entries_of(runs_folder(path))) {
    const std::string name = p.filename().string();
    if (!is_store_name(name) || name == except || !fs::is_directory(p, ec)) continue;
    const size_t n = list_store(p.string()).runs.size();
    stores.emplace_back(name, n);
    if (best.empty() || n > most) best = name, most = n;
  }
  for (const auto& [name, n] : stores)
    found.notes.push_back(name == best ? "its index was rebuilt from the " + std::to_string(n) + " run files of " + runs_folder(path) + "/" + name
                                       : runs_folder(path) + "/" + name + " (" + std::to_string(n) + " run files) is another store: removed");
  return best;
}

void collect_garbage(const std::string& path, const std::string& store, const StoreListing& listing, Upkeep& found) {
  std::error_code ec;
  const fs::path dir = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  for (const auto& p : entries_of(dir.string()))
    if (is_temporary_of(p.filename().string(), path) && fs::remove(p, ec)) found.removed.push_back(p.string());
  for (const auto& t : listing.temporaries)
    if (fs::remove(t, ec)) found.removed.push_back(t);
  for (const auto& p : entries_of(runs_folder(path))) {
    const std::string name = p.filename().string();
    if (name.starts_with("queue-")) {
      remove_unused_counter(p.string());  // a killed sweep's (file_lock.hpp)
    } else if (is_store_name(name) && name != store && fs::is_directory(p, ec)) {
      const size_t n = list_store(p.string()).runs.size();
      if (fs::remove_all(p, ec) != static_cast<std::uintmax_t>(-1))
        found.removed.push_back(p.string() + "/ (" + std::to_string(n) + " run files of a replaced file, or of a write that did not finish)");
    } else if ((name[0] == '.' && name.ends_with(".tmp")) || (!store.empty() && older_run_file(name))) {
      if (fs::remove(p, ec)) found.removed.push_back(p.string());
    }
  }
}

std::vector<std::string> unlisted_runs(const std::string& path, const StoreListing& listing, std::vector<std::string>* unindexed) {
  std::set<std::string> held, indexed;
  for (const auto& r : listing.runs) held.insert(r.name);
  H f = open_file(path);
  H runs = open_group(f, "/runs", path);
  std::vector<std::string> out;
  for (const auto& m : index_members(runs, path + ": /runs")) {
    indexed.insert(m.name);
    if (!held.count(m.name)) out.push_back(m.name);
  }
  if (unindexed)
    for (const auto& r : listing.runs)
      if (!indexed.count(r.name)) unindexed->push_back(r.name + " (in the store, not yet in the index)");
  return out;
}

RepairReport repair_results(const std::string& shown) {
  const std::string path = resolve_results_path(shown);
  std::error_code ec;
  if (!fs::exists(path, ec) && !fs::is_directory(runs_folder(path), ec))
    throw Error("repair: " + shown + ": no such results file (and no folder " + runs_folder(shown) + ")");
  const FileLock lock(results_lock_path(path), FileLock::Kind::exclusive, shown);
  const Guard guard;
  const IndexHead head = read_index_head(path);
  RepairReport rep;
  std::string store;
  if (head.kind == IndexHead::Kind::store && fs::is_directory(store_folder(path, head.store), ec)) store = head.store;
  else if (head.kind != IndexHead::Kind::older) store = store_to_adopt(path, "", rep.found);
  StoreListing listing;
  if (!store.empty()) {
    listing = list_store(store_folder(path, store));
    if (store == head.store)
      for (const auto& n : unlisted_runs(path, listing, &rep.found.relinked)) rep.found.dangling.push_back(n + ": its run file is gone");
    else
      for (const auto& r : listing.runs) rep.found.relinked.push_back(r.name);
  } else {
    if (head.kind == IndexHead::Kind::absent && !fs::exists(path, ec) && entries_of(runs_folder(path)).empty())
      throw Error("repair: " + shown + ": no index and no run files: nothing to repair");
    if (head.kind == IndexHead::Kind::older) {
      H f = open_file(path);
      H runs = open_group(f, "/runs", path);
      const auto members = index_members(runs, path + ": /runs");
      rep.packed = std::all_of(members.begin(), members.end(), [](const IndexMember& m) { return m.kind == IndexMember::Kind::group; });
      bool older_files = false;
      for (const auto& p : entries_of(runs_folder(path))) older_files = older_files || older_run_file(p.filename().string());
      if (rep.packed && !older_files) {  // what a killed first writer left is all there is to remove
        rep.runs = static_cast<int>(members.size());
        collect_garbage(path, "", StoreListing{}, rep.found);
        return rep;
      }
      rep.packed = false;
    }
    store = new_store_name();
    listing = move_into_store(path, head, store, rep.found);
  }
  IndexHead fixed = head;
  if (fixed.kind != IndexHead::Kind::store) fixed = new_index_head(store, head.writer.empty() ? writer_tag() + ":" + random_hex8() : head.writer);
  for (const auto& [k, v] : head.attrs) fixed.attrs.emplace(k, v);
  fixed.store = store;
  write_index(path, fixed, listing.runs, true);
  collect_garbage(path, store, listing, rep.found);
  rep.runs = static_cast<int>(listing.runs.size());
  return rep;
}

std::vector<std::string> upkeep_lines(const std::string& shown, const Upkeep& found) {
  std::vector<std::string> out;
  for (const auto& n : found.notes) out.push_back(shown + ": " + n);
  for (const auto& r : found.relinked) out.push_back(shown + ": relinked run " + r);
  for (const auto& d : found.dangling) out.push_back(shown + ": left out run " + d);
  return out;
}

}  // namespace xb
