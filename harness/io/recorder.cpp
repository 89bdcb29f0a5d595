#include "recorder.hpp"
#include "schema.hpp"

#include "atomic_file.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

namespace {

using namespace h5;

void write_run(hid_t file, const RunRecord& r) {
  H lcpl = link_create_plist();
  const std::string path = "/runs/" + r.name;
  if (H5Lexists(file, "/runs", H5P_DEFAULT) > 0 && H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0)
    throw Error("results file already has a run named '" + r.name + "'");
  H g(H5Gcreate2(file, path.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(g, "create group " + path);
  for (const auto& [k, v] : r.attrs) write_attr(g, k, v);
  for (const auto& [k, v] : r.datasets) write_dataset(g, k, v);
}

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

}  // namespace

void append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh) {
  for (const auto& r : runs) check_against_schema(r);
  std::error_code ec;
  const bool append = !fresh && fs::exists(path, ec);
  std::vector<char> image;
  {
    // The new file, in memory; closed (every object in it) before a byte reaches the disk.
    H file = append ? open_memory_file(read_file(path), path) : create_memory_file();
    if (!append) {
      write_attr(file, "schema_version", static_cast<long long>(schema_version));
      write_attr(file, "generator", std::string("xpbd-bench"));
    } else if (link_kind(file, "/runs") != Kind::group) {
      throw Error(path + ": not an xpbd-bench results file (no group /runs); refusing to append to it");
    }
    for (const auto& r : runs) write_run(file, r);
    image = file_image(file);
  }
  write_file_atomically(path, image.data(), image.size());
}

std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets, std::vector<std::string>* skipped) {
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

}  // namespace xb
