#include "recorder.hpp"
#include "schema.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

namespace {

using namespace h5;

struct Silence {  // HDF5 prints error stacks by default; we report our own messages.
  Silence() { silence_errors(); }
};
const Silence silence_hdf5;

// One run group: its attributes, and (with_datasets) every dataset in it, including those in
// subgroups, by relative path. Throws xb::Error naming `where` and the object.
RunRecord read_run(hid_t runs, const std::string& name, const std::string& where, bool with_datasets) {
  RunRecord r;
  r.name = name;
  const std::string run = where + ": run " + name;
  const Kind k = link_kind(runs, name);
  if (k != Kind::group) throw Error(run + " is " + kind_text(k) + ", not a run group");
  H g(H5Gopen2(runs, name.c_str(), H5P_DEFAULT), H5Gclose);
  if (g < 0) throw Error(run + ": cannot open");
  r.attrs = read_attrs(g, run);
  if (!with_datasets) return r;
  struct Ctx {
    RunRecord* r;
    std::string where, error;
  } ctx{&r, run + " dataset ", ""};
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
  if (e < 0) throw Error(run + ": cannot list its datasets");
  return r;
}

// "<pid>@<host>:<random>": who started a file (its attribute `writer`).
std::string new_writer_id() { return writer_tag() + ":" + random_hex8(); }

// "pid 123 on host" from a writer id, for messages.
std::string writer_words(const std::string& id) {
  const size_t at = id.find('@'), colon = id.rfind(':');
  if (at == std::string::npos || colon == std::string::npos || colon < at) return "'" + id + "'";
  return "pid " + id.substr(0, at) + " on " + id.substr(at + 1, colon - at - 1);
}

}  // namespace

ResultsWriter::ResultsWriter(std::string path, bool replace)
    : path_(std::move(path)), id_(new_writer_id()), replace_(replace) {}

std::vector<std::string> ResultsWriter::add(const std::vector<RunRecord>& runs) {
  for (const auto& r : runs) check_against_schema(r);  // before anything is written
  make_parent(path_);
  const FileLock lock(results_lock_path(path_), FileLock::Kind::exclusive, path_);
  const Guard guard;  // after the file lock (h5handle.hpp)
  const bool fresh = replace_ && !started_;
  std::error_code ec;
  RunFiles made(path_);  // run files of this add: removed again unless the new index links them
  Index index = !fresh && fs::exists(path_, ec) ? carry_index(path_, made) : new_index(id_);
  if (replace_ && started_ && index.writer != id_)
    throw Error(path_ + " was replaced by another writer (" + writer_words(index.writer) +
                ") after this command's first run; the file is that writer's now");
  std::vector<std::string> names;
  int number = next_run_number(index);
  for (const auto& r : runs) {
    char head[16];
    std::snprintf(head, sizeof head, "%04d_", number++);
    const std::string name = head + r.name;
    link_run(index, name, made.write(name, [&](hid_t file) { write_run(file, r, name); }));
    names.push_back(name);
  }
  commit_index(path_, index);
  made.keep();
  started_ = true;
  held_ = static_cast<int>(index.names.size());
  collect_garbage(path_, index, fresh);
  return names;
}

std::vector<std::string> append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh) {
  ResultsWriter w(path, fresh);
  return w.add(runs);
}

std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets, std::vector<std::string>* skipped) {
  const FileLock lock(results_lock_path(path), FileLock::Kind::shared, path);
  const Guard guard;
  H file = open_file(path);
  const Kind k = link_kind(file, "/runs");
  if (k == Kind::missing) throw Error(path + ": not an xpbd-bench results file (no group /runs)");
  if (k != Kind::group) throw Error(path + ": /runs is " + std::string(kind_text(k)) + ", expected the group of runs");
  H runs = open_group(file, "/runs", path);
  std::vector<RunRecord> out;
  for (const auto& name : link_names(runs, path + ": /runs")) {
    try {
      out.push_back(read_run(runs, name, path, with_datasets));
    } catch (const Error& e) {
      if (!skipped) throw;
      skipped->push_back(e.what());
    }
  }
  return out;
}

int count_runs(const std::string& path) {
  if (!fs::exists(path)) return 0;
  return static_cast<int>(read_runs(path, false).size());
}

std::vector<std::string> pack_runs(const std::string& src, const std::string& dst) {
  std::vector<char> image;
  std::vector<std::string> skipped;
  {
    const FileLock lock(results_lock_path(src), FileLock::Kind::shared, src);
    const Guard guard;
    image = packed_image(src, skipped);
  }
  make_parent(dst);
  if (!fs::exists(runs_folder(dst))) {
    write_file_atomically(dst, image.data(), image.size());
    return skipped;
  }
  // dst was a file of run files: replaced under its lock, its run files removed with it.
  const FileLock lock(results_lock_path(dst), FileLock::Kind::exclusive, dst);
  TmpFile out(dst, dst, true);
  out.write(image.data(), image.size());
  out.commit();
  const Guard guard;
  collect_garbage(dst, new_index(""), true);
  return skipped;
}

}  // namespace xb
