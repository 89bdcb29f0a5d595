// The readers of results files (recorder.hpp): every run, from the store's run files or, for a
// file without a store, from its index; no lock is taken, so no writer (a stopped one included)
// ever holds a reader up.
#include "recorder.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <functional>

namespace fs = std::filesystem;

namespace xb {

namespace {

using namespace h5;

// One run group (`object` under `loc`): its attributes, and (with_datasets) every dataset in it,
// including those in subgroups, by relative path. Throws xb::Error naming `where` and the object.
RunRecord read_run(hid_t loc, const std::string& object, const std::string& name, const std::string& where, bool with_datasets) {
  RunRecord r;
  r.name = name;
  const Kind k = link_kind(loc, object);
  if (k != Kind::group) throw Error(where + " is " + kind_text(k) + ", not a run group");
  H g(H5Gopen2(loc, object.c_str(), H5P_DEFAULT), H5Gclose);
  if (g < 0) throw Error(where + ": cannot open");
  r.attrs = read_attrs(g, where);
  if (!with_datasets) return r;
  struct Ctx {
    RunRecord* r;
    std::string where, error;
  } ctx{&r, where + " dataset ", ""};
  // No exception may cross HDF5's C frames: the callback stops the walk and keeps the message.
  const herr_t e = H5Ovisit2(
      g, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t obj, const char* nm, const H5O_info_t* oinfo, void* data) -> herr_t {
        if (oinfo->type != H5O_TYPE_DATASET) return 0;
        auto* c = static_cast<Ctx*>(data);
        try {
          H ds(H5Dopen2(obj, nm, H5P_DEFAULT), H5Dclose);
          if (ds < 0) throw Error(c->where + nm + ": cannot open");
          c->r->datasets[nm] = read_dataset(ds, c->where + nm);
        } catch (const std::exception& ex) {
          c->error = ex.what();
          return -1;
        }
        return 0;
      },
      &ctx, H5O_INFO_BASIC);
  if (!ctx.error.empty()) throw Error(ctx.error);
  if (e < 0) throw Error(where + ": cannot list its datasets");
  return r;
}

// visit(loc, object, name, where) for each run's group; bad(message) for a run that cannot be reached.
using Visit = std::function<void(hid_t, const std::string&, const std::string&, const std::string&)>;
using Bad = std::function<void(const std::string&)>;

void each_stored_run(const std::string& shown, const std::string& path, const IndexHead& head, const Visit& visit, const Bad& bad) {
  const std::string folder = store_folder_of(path, head);
  StoreListing listing = list_store(folder);
  if (!listing.exists) {
    bad(shown + ": its runs folder " + runs_folder(shown) + "/" + head.store +
        " is missing (moved, renamed or not copied with it?): none of its runs can be read");
    return;
  }
  for (const auto& r : listing.runs) {
    const std::string where = shown + ": run " + r.name;
    H f(H5I_INVALID_HID, nullptr);
    try {
      f = open_file(folder + "/" + r.file);
    } catch (const Error& e) {
      bad(where + ": " + e.what());
      continue;
    }
    std::string name = r.name;  // a run file renamed by hand still holds its run under its own name
    if (H5Lexists(f, "/runs", H5P_DEFAULT) > 0 && H5Lexists(f, ("/runs/" + name).c_str(), H5P_DEFAULT) <= 0) {
      H g(H5Gopen2(f, "/runs", H5P_DEFAULT), H5Gclose);
      const auto members = g < 0 ? std::vector<IndexMember>{} : index_members(g, where);
      if (members.size() == 1) name = members[0].name;
    }
    visit(f, "/runs/" + name, name, shown + ": run " + name);
  }
  try {
    for (const auto& n : unlisted_runs(path, listing))
      bad(shown + ": run " + n + " is listed by the index but its run file is gone from " + folder);
  } catch (const Error&) {  // the index changed meanwhile (a writer replaced it): nothing to add
  }
}

void each_run(const std::string& shown, const Visit& visit, const Bad& bad) {
  const std::string path = resolve_results_path(shown);
  IndexHead head = read_index_head(path);
  if (head.kind == IndexHead::Kind::absent) throw Error(shown + ": no such file");
  if (head.kind == IndexHead::Kind::store) {
    if (!fs::is_directory(store_folder_of(path, head))) head = read_index_head(path);  // replaced meanwhile?
    return each_stored_run(shown, path, head, visit, bad);
  }
  H f = open_file(path);
  H runs = open_group(f, "/runs", shown);
  for (const auto& m : index_members(runs, shown + ": /runs")) {
    const std::string where = shown + ": run " + m.name;
    if (m.kind != IndexMember::Kind::external) {
      visit(runs, m.name, m.name, where);
      continue;
    }
    // A link of the earlier layout, followed as this project resolves it (not from the working directory).
    const std::string target = link_target(path, m.file);
    std::error_code ec;
    if (!fs::exists(target, ec)) {
      bad(where + " is a dangling link (to " + m.file + ", not beside " + shown + ")");
      continue;
    }
    H t(H5I_INVALID_HID, nullptr);
    try {
      t = open_file(target);
    } catch (const Error& e) {
      bad(where + " is a dangling link (" + e.what() + ")");
      continue;
    }
    visit(t, m.object, m.name, where);
  }
}

}  // namespace

std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets, std::vector<std::string>* skipped) {
  const Guard guard;
  std::vector<RunRecord> out;
  const Bad bad = [&](const std::string& e) {
    if (!skipped) throw Error(e);
    skipped->push_back(e);
  };
  each_run(
      path,
      [&](hid_t loc, const std::string& object, const std::string& name, const std::string& where) {
        try {
          out.push_back(read_run(loc, object, name, where, with_datasets));
        } catch (const Error& e) {
          bad(e.what());
        }
      },
      bad);
  std::stable_sort(out.begin(), out.end(), [](const RunRecord& a, const RunRecord& b) { return a.name < b.name; });
  return out;
}

int count_runs(const std::string& shown) {
  const std::string path = resolve_results_path(shown);
  std::error_code ec;
  if (!fs::exists(path, ec)) return 0;
  const Guard guard;
  const IndexHead head = read_index_head(path);
  if (head.kind == IndexHead::Kind::store) return static_cast<int>(list_store(store_folder_of(path, head)).runs.size());
  H f = open_file(path);
  H runs = open_group(f, "/runs", shown);
  return static_cast<int>(index_members(runs, shown + ": /runs").size());
}

std::vector<std::string> pack_runs(const std::string& src, const std::string& dst_shown) {
  std::vector<std::string> skipped;
  std::vector<char> image;
  {
    const Guard guard;
    H out = create_memory_file();
    {
      const IndexHead head = read_index_head(resolve_results_path(src));
      for (const auto& [key, v] : head.attrs)
        if (key != "writer" && key != "store" && key != "links_to" && key != "runs_indexed") write_attr(out, key, v);
    }
    H out_runs(H5Gcreate2(out, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    check_id(out_runs, "create group /runs");
    const Bad bad = [&](const std::string& e) { skipped.push_back(e); };
    each_run(
        src,
        [&](hid_t loc, const std::string& object, const std::string& name, const std::string& where) {
          const Kind k = link_kind(loc, object);
          if (k != Kind::group) return bad(where + " is " + kind_text(k) + ", not a run group");
          // The run's group itself, with everything in it.
          check(H5Ocopy(loc, object.c_str(), out_runs, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), "copy run " + name);
        },
        bad);
    image = file_image(out);
  }
  const std::string dst = resolve_results_path(dst_shown);
  make_parent(dst);
  if (!fs::exists(runs_folder(dst))) {
    write_file_atomically(dst, image.data(), image.size());
    return skipped;
  }
  // dst was a results file with a store: replaced under its lock, its run files removed with it.
  const FileLock lock(results_lock_path(dst), FileLock::Kind::exclusive, dst_shown);
  TmpFile out(dst, dst_shown, true);
  out.write(image.data(), image.size());
  out.commit();
  const Guard guard;
  Upkeep found;
  collect_garbage(dst, "", StoreListing{}, found);
  return skipped;
}

}  // namespace xb
