#include "recorder.hpp"

#include "../problems/error.hpp"

#include <hdf5.h>

#include <cstdio>
#include <filesystem>
#include <fcntl.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace xb {

namespace {

// Closes an HDF5 handle when it goes out of scope.
struct H {
  hid_t id;
  herr_t (*close)(hid_t);
  H(hid_t i, herr_t (*c)(hid_t)) : id(i), close(c) {}
  ~H() {
    if (id >= 0) close(id);
  }
  H(const H&) = delete;
  H& operator=(const H&) = delete;
  operator hid_t() const { return id; }
};

void check(herr_t e, const std::string& what) {
  if (e < 0) throw Error("HDF5: " + what + " failed");
}
void check_id(hid_t id, const std::string& what) {
  if (id < 0) throw Error("HDF5: " + what + " failed");
}

hid_t string_type() {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

void write_attr(hid_t obj, const std::string& name, const AttrValue& v) {
  H space(H5Screate(H5S_SCALAR), H5Sclose);
  if (auto* i = std::get_if<long long>(&v)) {
    H a(H5Acreate2(obj, name.c_str(), H5T_NATIVE_LLONG, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    check(H5Awrite(a, H5T_NATIVE_LLONG, i), "write attribute " + name);
  } else if (auto* d = std::get_if<double>(&v)) {
    H a(H5Acreate2(obj, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    check(H5Awrite(a, H5T_NATIVE_DOUBLE, d), "write attribute " + name);
  } else {
    H t(string_type(), H5Tclose);
    H a(H5Acreate2(obj, name.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    const char* s = std::get<std::string>(v).c_str();
    check(H5Awrite(a, t, &s), "write attribute " + name);
  }
}

void write_dataset(hid_t group, const std::string& name, const DataValue& v) {
  H lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  H5Pset_create_intermediate_group(lcpl, 1);
  hsize_t n = std::visit([](const auto& x) { return static_cast<hsize_t>(x.size()); }, v);
  H space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  if (auto* d = std::get_if<std::vector<double>>(&v)) {
    H ds(H5Dcreate2(group, name.c_str(), H5T_NATIVE_DOUBLE, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    check_id(ds, "dataset " + name);
    if (n) check(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d->data()), "write " + name);
  } else if (auto* i = std::get_if<std::vector<long long>>(&v)) {
    H ds(H5Dcreate2(group, name.c_str(), H5T_NATIVE_LLONG, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    check_id(ds, "dataset " + name);
    if (n) check(H5Dwrite(ds, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, i->data()), "write " + name);
  } else {
    const auto& s = std::get<std::vector<std::string>>(v);
    std::vector<const char*> ptrs;
    for (const auto& x : s) ptrs.push_back(x.c_str());
    H t(string_type(), H5Tclose);
    H ds(H5Dcreate2(group, name.c_str(), t, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    check_id(ds, "dataset " + name);
    if (n) check(H5Dwrite(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()), "write " + name);
  }
}

AttrValue read_attr(hid_t a) {
  H t(H5Aget_type(a), H5Tclose);
  switch (H5Tget_class(t)) {
    case H5T_INTEGER: {
      long long v = 0;
      check(H5Aread(a, H5T_NATIVE_LLONG, &v), "read attribute");
      return v;
    }
    case H5T_FLOAT: {
      double v = 0;
      check(H5Aread(a, H5T_NATIVE_DOUBLE, &v), "read attribute");
      return v;
    }
    case H5T_STRING: {
      if (H5Tis_variable_str(t)) {
        char* s = nullptr;
        H mt(string_type(), H5Tclose);
        check(H5Aread(a, mt, &s), "read attribute");
        std::string out = s ? s : "";
        H5free_memory(s);
        return out;
      }
      std::string out(H5Tget_size(t), '\0');
      check(H5Aread(a, t, out.data()), "read attribute");
      return std::string(out.c_str());
    }
    default: return std::string("<unsupported>");
  }
}

DataValue read_dataset(hid_t ds) {
  H t(H5Dget_type(ds), H5Tclose);
  H space(H5Dget_space(ds), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  switch (H5Tget_class(t)) {
    case H5T_INTEGER: {
      std::vector<long long> v(n);
      if (n) check(H5Dread(ds, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read dataset");
      return v;
    }
    case H5T_FLOAT: {
      std::vector<double> v(n);
      if (n) check(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read dataset");
      return v;
    }
    default: {
      std::vector<char*> p(n, nullptr);
      H mt(string_type(), H5Tclose);
      if (n) check(H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), "read dataset");
      std::vector<std::string> v;
      for (char* s : p) {
        v.push_back(s ? s : "");
        H5free_memory(s);
      }
      return v;
    }
  }
}

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
  Silence() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
};
const Silence silence_hdf5;

}  // namespace

void append_runs(const std::string& path, const std::vector<RunRecord>& runs, bool fresh) {
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
