#include "h5_edits.hpp"

#include "fuzz_input.hpp"
#include "h5_values.hpp"

#include "harness/io/h5io.hpp"

#include <fuzzer/FuzzedDataProvider.h>
#include <sanitizer/lsan_interface.h>
#include <hdf5.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using xb::h5::H;

namespace xb_fuzz {
namespace {

// The seeds of a folder, read once, in name order.
const std::vector<std::string>& seeds(const std::string& dir) {
  static std::map<std::string, std::vector<std::string>> cache;
  auto& s = cache[dir];
  if (!s.empty()) return s;
  std::vector<fs::path> paths;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == ".h5") paths.push_back(e.path());
  std::sort(paths.begin(), paths.end());
  for (const auto& p : paths) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    s.push_back(bytes.str());
  }
  if (s.empty()) {
    std::fprintf(stderr, "fuzz: no seed files in %s\n", dir.c_str());
    std::abort();
  }
  return s;
}

hid_t new_lcpl() {  // intermediate groups are created as needed
  const hid_t p = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(p, 1);
  return p;
}

// A 1-D numeric dataset's values, as integers or doubles by its type class.
struct Values {
  bool integer = false;
  std::vector<long long> i;
  std::vector<double> d;
  size_t size() const { return integer ? i.size() : d.size(); }
};

bool read_values(hid_t f, const std::string& p, Values& v) {
  if (H5Oexists_by_name(f, p.c_str(), H5P_DEFAULT) <= 0) return false;
  H5O_info_t oi;
  if (H5Oget_info_by_name2(f, p.c_str(), &oi, H5O_INFO_BASIC, H5P_DEFAULT) < 0 || oi.type != H5O_TYPE_DATASET) return false;
  H ds(H5Dopen2(f, p.c_str(), H5P_DEFAULT), H5Dclose);
  H t(H5Dget_type(ds), H5Tclose);
  H s(H5Dget_space(ds), H5Sclose);
  const H5T_class_t c = H5Tget_class(t);
  const hssize_t n = H5Sget_simple_extent_npoints(s);
  if ((c != H5T_INTEGER && c != H5T_FLOAT) || H5Sget_simple_extent_ndims(s) != 1 || n < 0 || n > 100000) return false;
  v.integer = c == H5T_INTEGER;
  (v.integer ? v.i.resize(n) : v.d.resize(n));
  void* buf = v.integer ? static_cast<void*>(v.i.data()) : v.d.data();
  return n == 0 || H5Dread(ds, v.integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0;
}

void write_values(hid_t f, const std::string& p, const Values& v) {
  H5Ldelete(f, p.c_str(), H5P_DEFAULT);
  const hsize_t n = v.size();
  const hid_t type = v.integer ? H5T_NATIVE_LLONG : H5T_NATIVE_DOUBLE;
  H lcpl(new_lcpl(), H5Pclose);
  H space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  H ds(H5Dcreate2(f, p.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
  const void* buf = v.integer ? static_cast<const void*>(v.i.data()) : v.d.data();
  if (ds >= 0 && n) H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
}

// Edits the values of a 1-D numeric dataset: one entry set, the length changed, two entries
// swapped, or every entry scaled (integers wrap, as unsigned arithmetic does).
void edit_values(FuzzedDataProvider& in, hid_t f, const std::string& p) {
  Values v;
  if (!read_values(f, p, v)) return;
  const size_t n = v.size();
  switch (in.ConsumeIntegralInRange(0, 3)) {
    case 0:
      if (n == 0) return;
      if (v.integer) v.i[in.ConsumeIntegralInRange<size_t>(0, n - 1)] = integer(in);
      else v.d[in.ConsumeIntegralInRange<size_t>(0, n - 1)] = number(in);
      break;
    case 1: {
      const size_t m = in.ConsumeIntegralInRange<size_t>(0, n + 8);
      if (v.integer) v.i.resize(m, integer(in));
      else v.d.resize(m, number(in));
      break;
    }
    case 2:
      if (n == 0) return;
      if (v.integer) std::swap(v.i[in.ConsumeIntegralInRange<size_t>(0, n - 1)], v.i[in.ConsumeIntegralInRange<size_t>(0, n - 1)]);
      else std::swap(v.d[in.ConsumeIntegralInRange<size_t>(0, n - 1)], v.d[in.ConsumeIntegralInRange<size_t>(0, n - 1)]);
      break;
    default: {
      const long long ki = integer(in);
      const double kd = number(in);
      for (auto& x : v.i) x = static_cast<long long>(static_cast<unsigned long long>(x) * static_cast<unsigned long long>(ki));
      for (auto& x : v.d) x *= kd;
    }
  }
  write_values(f, p, v);
}

// A new dataset at p: any type and shape, contiguous, compact, chunked or deflated.
void new_dataset(FuzzedDataProvider& in, hid_t f, const std::string& p, hsize_t hint) {
  H5Ldelete(f, p.c_str(), H5P_DEFAULT);
  H t(make_type(in), H5Tclose);
  bool huge = false;
  H space(make_space(in, true, hint, huge), H5Sclose);
  H dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const int layout = huge ? 2 : in.ConsumeIntegralInRange(0, 3);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (layout == 1) H5Pset_layout(dcpl, H5D_COMPACT);
  if (layout >= 2 && rank > 0) {  // chunks of up to 64 values a dimension, any extent allowed
    hsize_t dims[3], chunk[3], max[3] = {H5S_UNLIMITED, H5S_UNLIMITED, H5S_UNLIMITED};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    for (int k = 0; k < rank; ++k) chunk[k] = std::clamp<hsize_t>(dims[k], 1, 64);
    H5Sset_extent_simple(space, rank, dims, max);
    H5Pset_chunk(dcpl, rank, chunk);
    if (layout == 3) H5Pset_deflate(dcpl, 6);
  }
  H lcpl(new_lcpl(), H5Pclose);
  H ds(H5Dcreate2(f, p.c_str(), t, space, lcpl, dcpl, H5P_DEFAULT), H5Dclose);
  if (ds < 0 || huge) return;
  write_data(in, t, H5Sget_simple_extent_npoints(space),
             [&](hid_t mt, const void* buf) { H5Dwrite(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf); });
}

// Replaces (or adds) attribute `name` of the object at p with one of any type and shape.
void new_attribute(FuzzedDataProvider& in, hid_t f, const std::string& p, const std::string& name) {
  if (H5Oexists_by_name(f, p.c_str(), H5P_DEFAULT) <= 0) return;
  H obj(H5Oopen(f, p.c_str(), H5P_DEFAULT), H5Oclose);
  if (obj < 0) return;
  H5Adelete(obj, name.c_str());
  if (in.ConsumeBool()) return;  // the attribute is now missing
  H t(make_type(in), H5Tclose);
  bool huge = false;
  H space(make_space(in, false, 1, huge), H5Sclose);
  H a(H5Acreate2(obj, name.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (a < 0) return;
  write_data(in, t, H5Sget_simple_extent_npoints(space), [&](hid_t mt, const void* buf) { H5Awrite(a, mt, buf); });
}

// Every link under the root, as absolute paths.
std::vector<std::string> link_paths(hid_t f) {
  std::vector<std::string> out{"/"};
  H5Lvisit(
      f, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t, const char* name, const H5L_info_t*, void* d) -> herr_t {
        static_cast<std::vector<std::string>*>(d)->push_back(std::string("/") + name);
        return 0;
      },
      &out);
  return out;
}

// The attribute names of the object at p.
std::vector<std::string> attr_names(hid_t f, const std::string& p) {
  std::vector<std::string> out;
  if (H5Oexists_by_name(f, p.c_str(), H5P_DEFAULT) <= 0) return out;
  H5Aiterate_by_name(
      f, p.c_str(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5A_info_t*, void* d) -> herr_t {
        static_cast<std::vector<std::string>*>(d)->push_back(name);
        return 0;
      },
      &out, H5P_DEFAULT);
  return out;
}

// After a file libhdf5 could not close (rare, after many copies), ids it keeps are not the
// reader's: the reader is judged on what it adds to `left_open`.
int generation = 0;
ssize_t left_open = 0;

struct Editor {
  FuzzedDataProvider& in;
  hid_t f;
  std::vector<std::string> paths, attrs;  // links in the file or looked for; attribute names looked for

  const std::string& pick(const std::vector<std::string>& v) { return v[in.ConsumeIntegralInRange<size_t>(0, v.size() - 1)]; }
  hsize_t length_of(const std::string& p) {
    Values v;
    return read_values(f, p, v) ? v.size() : 4;
  }
  void edit_link(int op, const std::string& p) {
    const std::string& q = pick(paths);
    H lcpl(new_lcpl(), H5Pclose);
    H5Ldelete(f, p.c_str(), H5P_DEFAULT);
    switch (op) {
      case 0: return;  // missing
      case 1: H5Lcreate_soft(in.ConsumeBool() ? q.c_str() : "/nothing/here", f, p.c_str(), lcpl, H5P_DEFAULT); return;
      case 2: H5Lcreate_hard(f, q.c_str(), f, p.c_str(), lcpl, H5P_DEFAULT); return;
      case 3: H5Lcreate_external("missing.h5", "/x", f, p.c_str(), lcpl, H5P_DEFAULT); return;
      case 4: H5Gclose(H5Gcreate2(f, p.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT)); return;
      default: H5Tcommit2(f, p.c_str(), H(H5Tcopy(H5T_NATIVE_INT), H5Tclose), lcpl, H5P_DEFAULT, H5P_DEFAULT);
    }
  }
  // Copies the object at q (a run, a matrix group) to new names: many runs, repeated members.
  // Immediate members only: a group holding a hard link to itself would be copied without end.
  void copy(const std::string& q) {
    const int k = in.ConsumeIntegralInRange(1, 40);
    H ocpypl(H5Pcreate(H5P_OBJECT_COPY), H5Pclose);
    H5Pset_copy_object(ocpypl, H5O_COPY_SHALLOW_HIERARCHY_FLAG);
    for (int j = 0; j < k && q != "/"; ++j) {
      const std::string p = q + "_" + std::to_string(j);
      if (H5Ocopy(f, q.c_str(), f, p.c_str(), ocpypl, H5P_DEFAULT) >= 0) paths.push_back(p);
    }
  }
  void edit() {
    const std::string p = pick(paths);
    switch (in.ConsumeIntegralInRange(0, 7)) {
      case 0: edit_values(in, f, p); return;
      case 1: new_dataset(in, f, p, length_of(p)); return;
      case 2: {
        auto names = attr_names(f, p);
        names.insert(names.end(), attrs.begin(), attrs.end());
        new_attribute(in, f, p, pick(names));
        return;
      }
      case 3: copy(p); return;
      default: edit_link(in.ConsumeIntegralInRange(0, 5), p);
    }
  }
};

}  // namespace

std::string build_h5(const std::string& seed_dir, const std::string& file, const std::vector<std::string>& names,
                     const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  // The builder is not under test: what libhdf5 leaks while writing (after a failed close) is not
  // the reader's leak.
  struct NoLeakCheck {
    NoLeakCheck() { __lsan_disable(); }
    ~NoLeakCheck() { __lsan_enable(); }
  } no_leak_check;
  const auto& s = seeds(seed_dir);
  const std::string path = write_file(std::to_string(generation) + file, s[in.ConsumeIntegralInRange<size_t>(0, s.size() - 1)]);
  bool closed = false;
  xb::h5::silence_errors();
  {
    H fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);  // nothing of ours stays open past H5Fclose
    H f(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl), H5Fclose);
    if (f < 0) {
      std::fprintf(stderr, "fuzz: cannot open %s for writing\n", path.c_str());
      std::abort();
    }
    Editor e{in, f, link_paths(f), {}};
    for (const auto& n : names) (n[0] == '/' ? e.paths : e.attrs).push_back(n);
    for (int k = 0; k < 32 && in.remaining_bytes() > 0; ++k) e.edit();
    closed = H5Fclose(f.id) >= 0;
    f.id = -1;
  }
  left_open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
  if (!closed) {  // libhdf5 keeps the file open: later inputs get a new name, this one is not read
    std::fprintf(stderr, "fuzz: libhdf5 could not close the file the edits wrote (input skipped)\n");
    ++generation;
    return "";
  }
  if (const char* keep = std::getenv("XB_FUZZ_KEEP")) fs::copy_file(path, keep, fs::copy_options::overwrite_existing);
  return path;
}

void expect_no_open_handles() {
  const ssize_t open = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
  if (open != left_open) {
    std::fprintf(stderr, "fuzz: the reader left %zd HDF5 objects open\n", open - left_open);
    std::abort();
  }
}

}  // namespace xb_fuzz
