#include "recorder.hpp"
#include "schema.hpp"

#include "h5io.hpp"

#include "../../core/error.hpp"

#include <hdf5.h>

#include <cstdio>
#include <filesystem>
#include <fcntl.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace xb {

std::string attr_value_text(const AttrValue& v, int digits) {
  if (auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&v)) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", digits, *d);
    return b;
  }
  return std::get<std::string>(v);
}

namespace {

using namespace h5;


void write_run(hid_t file, const RunRecord& r) {
  H lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl, 1);
  const std::string path = "/runs/" + r.name;
  if (H5Lexists(file, "/runs", H5P_DEFAULT) > 0 && H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0)
    throw Error("results file already has a run named '" + r.name + "'");
  H g(H5Gcreate2(file, path.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(g, "create group " + path);
  for (const auto& [k, v] : r.attrs) write_attr(g, k, v);
  for (const auto& [k, v] : r.datasets) write_dataset(g, k, v);
}

void fsync_path(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

struct Silence {  // HDF5 prints error stacks by default; we report our own messages.
  Silence() { silence_errors(); }
};
const Silence silence_hdf5;

}  // namespace

void append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh) {
  for (const auto& r : runs) check_against_schema(r);
  const std::string tmp = path + ".tmp";
  std::error_code ec;
  fs::remove(tmp, ec);
  hid_t fid;
  if (!fresh && fs::exists(path)) {
    fs::copy_file(path, tmp, fs::copy_options::overwrite_existing, ec);
    if (ec) throw Error("cannot copy " + path + " to " + tmp + ": " + ec.message());
    fid = H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (fid < 0) throw Error(path + ": not a readable HDF5 results file");
  } else {
    if (path.find('/') != std::string::npos) fs::create_directories(fs::path(path).parent_path(), ec);
    fid = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (fid < 0) throw Error("cannot create " + tmp);
    write_attr(fid, "schema_version", static_cast<long long>(schema_version));
    write_attr(fid, "generator", std::string("xpbd-bench"));
  }
  try {
    H file(fid, H5Fclose);
    for (const auto& r : runs) write_run(file, r);
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush");
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fsync_path(tmp);
  fs::rename(tmp, path, ec);
  if (ec) throw Error("cannot rename " + tmp + " to " + path + ": " + ec.message());
  fsync_path(fs::path(path).has_parent_path() ? fs::path(path).parent_path().string() : ".");
}

std::vector<RunRecord> read_runs(const std::string& path, bool with_datasets) {
  if (!fs::exists(path)) throw Error(path + ": no such file");
  hid_t fid = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (fid < 0) throw Error(path + ": not an HDF5 file");
  H file(fid, H5Fclose);
  std::vector<RunRecord> out;
  if (H5Lexists(file, "/runs", H5P_DEFAULT) <= 0) return out;
  H runs(H5Gopen2(file, "/runs", H5P_DEFAULT), H5Gclose);
  H5G_info_t info;
  check(H5Gget_info(runs, &info), "group info");
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[1024];
    H5Lget_name_by_idx(runs, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    RunRecord r;
    r.name = name;
    H g(H5Gopen2(runs, name, H5P_DEFAULT), H5Gclose);
    H5O_info_t oi;
    H5Oget_info2(g, &oi, H5O_INFO_NUM_ATTRS);
    for (hsize_t a = 0; a < oi.num_attrs; ++a) {
      H attr(H5Aopen_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, a, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
      char an[1024];
      H5Aget_name(attr, sizeof an, an);
      r.attrs[an] = read_attr(attr);
    }
    if (with_datasets) {
      // Every dataset in the run group, including those in subgroups, by its relative path.
      struct Ctx {
        RunRecord* r;
      } ctx{&r};
      H5Ovisit2(
          g, H5_INDEX_NAME, H5_ITER_INC,
          [](hid_t obj, const char* nm, const H5O_info_t* oinfo, void* data) -> herr_t {
            if (oinfo->type != H5O_TYPE_DATASET) return 0;
            H ds(H5Dopen2(obj, nm, H5P_DEFAULT), H5Dclose);
            static_cast<Ctx*>(data)->r->datasets[nm] = read_dataset(ds);
            return 0;
          },
          &ctx, H5O_INFO_BASIC);
    }
    out.push_back(std::move(r));
  }
  return out;
}

int count_runs(const std::string& path) {
  if (!fs::exists(path)) return 0;
  return static_cast<int>(read_runs(path, false).size());
}

}  // namespace xb
