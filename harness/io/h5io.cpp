#include "h5io.hpp"

#include "../../core/error.hpp"

#include <atomic>
#include <cstring>
#include <filesystem>
#include <vector>

namespace fs = std::filesystem;

namespace xb::h5 {

void check(herr_t e, const std::string& what) {
  if (e < 0) throw Error("HDF5: " + what + " failed");
}
void check_id(hid_t id, const std::string& what) {
  if (id < 0) throw Error("HDF5: " + what + " failed");
}

H string_type() {
  H t(H5Tcopy(H5T_C_S1), H5Tclose);
  check_id(t, "string type");
  check(H5Tset_size(t, H5T_VARIABLE), "string type");
  check(H5Tset_cset(t, H5T_CSET_UTF8), "string type");
  return t;
}

void write_attr(hid_t obj, const std::string& name, const AttrValue& v) {
  H space(H5Screate(H5S_SCALAR), H5Sclose);
  check_id(space, "dataspace of attribute " + name);
  if (auto* i = std::get_if<long long>(&v)) {
    H a(H5Acreate2(obj, name.c_str(), H5T_NATIVE_LLONG, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    check(H5Awrite(a, H5T_NATIVE_LLONG, i), "write attribute " + name);
  } else if (auto* d = std::get_if<double>(&v)) {
    H a(H5Acreate2(obj, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    check(H5Awrite(a, H5T_NATIVE_DOUBLE, d), "write attribute " + name);
  } else {
    H t = string_type();
    H a(H5Acreate2(obj, name.c_str(), t, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check_id(a, "attribute " + name);
    const char* s = std::get<std::string>(v).c_str();
    check(H5Awrite(a, t, &s), "write attribute " + name);
  }
}

void write_dataset(hid_t group, const std::string& name, const DataValue& v) {
  H lcpl = link_create_plist();
  hsize_t n = std::visit([](const auto& x) { return static_cast<hsize_t>(x.size()); }, v);
  H space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  check_id(space, "dataspace of " + name);
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
    H t = string_type();
    H ds(H5Dcreate2(group, name.c_str(), t, space, lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    check_id(ds, "dataset " + name);
    if (n) check(H5Dwrite(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()), "write " + name);
  }
}

namespace {
// Element counts above this are refused before any allocation: no results or system array comes
// near it, and a damaged header must not ask for terabytes.
constexpr hssize_t max_elements = hssize_t{1} << 31;

// The number of elements of a dataspace; throws unless it is scalar or 1-D (attributes: one element).
hssize_t extent(hid_t space, const std::string& where, bool attribute) {
  if (space < 0) throw Error(where + ": cannot read its shape");
  const int nd = H5Sget_simple_extent_ndims(space);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (nd < 0 || n < 0) throw Error(where + ": cannot read its shape");
  if (H5Sget_simple_extent_type(space) == H5S_NULL) throw Error(where + ": has no value (null dataspace)");
  if (attribute && n != 1)
    throw Error(where + ": is an array of " + std::to_string(n) + " values, expected a single value");
  if (!attribute && nd != 1) throw Error(where + ": has " + std::to_string(nd) + " dimensions, expected a 1-D array");
  if (n > max_elements) throw Error(where + ": declares " + std::to_string(n) + " values, more than can be read");
  return n;
}

// The file must hold a dataset's values before they are allocated: a huge declared extent over
// chunks never written (or an unallocated contiguous dataset) would otherwise ask for gigabytes
// from a file of kilobytes. Our writers store every value; with a filter (compression), up to
// 1100 bytes per stored byte are allowed (deflate's limit is about 1032:1).
void check_stored(hid_t ds, hid_t type, hssize_t n, const std::string& where) {
  if (n == 0) return;
  H dcpl(H5Dget_create_plist(ds), H5Pclose);
  const int filters = dcpl < 0 ? -1 : H5Pget_nfilters(dcpl);
  if (filters < 0) throw Error(where + ": cannot read its storage properties");
  const double declared = static_cast<double>(n) * static_cast<double>(H5Tget_size(type));
  const double stored = static_cast<double>(H5Dget_storage_size(ds));
  if (declared > stored * (filters == 0 ? 1 : 1100))
    throw Error(where + ": declares " + std::to_string(n) + " values (" + std::to_string(static_cast<long long>(declared)) +
                " bytes) but the file stores only " + std::to_string(static_cast<long long>(stored)) + " bytes of them");
}

// Fixed-length string values of `size` bytes each, NUL-padded or not: each to its first NUL.
std::vector<std::string> split_fixed(const std::vector<char>& buf, size_t size, hssize_t n) {
  std::vector<std::string> out;
  for (hssize_t i = 0; i < n; ++i) {
    const char* p = buf.data() + i * size;
    out.emplace_back(p, strnlen(p, size));
  }
  return out;
}

// n strings of the string type `t` through `read(memtype, buffer)` (H5Aread or H5Dread).
template <class Read>
std::vector<std::string> read_strings(hid_t t, hssize_t n, const std::string& where, Read read) {
  const htri_t vlen = H5Tis_variable_str(t);
  if (vlen < 0) throw Error(where + ": cannot read its string type");
  if (vlen) {
    H mt(H5Tcopy(t), H5Tclose);  // same character set as the file: no conversion path needed
    check_id(mt, where + ": string type");
    std::vector<char*> p(n, nullptr);
    if (read(mt.id, p.data()) < 0) throw Error(where + ": cannot read its strings");
    std::vector<std::string> out;
    for (char* c : p) {
      out.emplace_back(c ? c : "");
      H5free_memory(c);
    }
    return out;
  }
  const size_t size = H5Tget_size(t);
  if (size == 0 || size > (size_t{1} << 24)) throw Error(where + ": fixed-length strings of " + std::to_string(size) + " bytes");
  if (static_cast<double>(size) * n > 1e9) throw Error(where + ": " + std::to_string(n) + " strings of " + std::to_string(size) + " bytes, too large");
  std::vector<char> buf(size * n + 1, '\0');
  if (read(t, buf.data()) < 0) throw Error(where + ": cannot read its strings");
  return split_fixed(buf, size, n);
}
}  // namespace

AttrValue read_attr(hid_t a, const std::string& where) {
  H t(H5Aget_type(a), H5Tclose);
  if (t < 0) throw Error(where + ": cannot read its type");
  H space(H5Aget_space(a), H5Sclose);
  extent(space, where, true);
  auto read = [&](hid_t mt, void* buf) { return H5Aread(a, mt, buf); };
  switch (H5Tget_class(t)) {
    case H5T_INTEGER: {
      long long v = 0;
      if (read(H5T_NATIVE_LLONG, &v) < 0) throw Error(where + ": cannot read it as an integer");
      return v;
    }
    case H5T_FLOAT: {
      double v = 0;
      if (read(H5T_NATIVE_DOUBLE, &v) < 0) throw Error(where + ": cannot read it as a number");
      return v;
    }
    case H5T_STRING: return read_strings(t, 1, where, read)[0];
    default: throw Error(where + ": has an unsupported type (expected an integer, a float or a string)");
  }
}

std::map<std::string, AttrValue> read_attrs(hid_t obj, const std::string& where) {
  H5O_info_t oi;
  if (H5Oget_info2(obj, &oi, H5O_INFO_NUM_ATTRS) < 0) throw Error(where + ": cannot list its attributes");
  std::map<std::string, AttrValue> out;
  for (hsize_t i = 0; i < oi.num_attrs; ++i) {
    H a(H5Aopen_by_idx(obj, ".", H5_INDEX_NAME, H5_ITER_INC, i, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (a < 0) throw Error(where + ": cannot open attribute #" + std::to_string(i));
    const ssize_t len = H5Aget_name(a, 0, nullptr);
    if (len < 0) throw Error(where + ": cannot read the name of attribute #" + std::to_string(i));
    std::string name(len + 1, '\0');
    H5Aget_name(a, name.size(), name.data());
    name.resize(len);
    out[name] = read_attr(a, where + " attribute '" + name + "'");
  }
  return out;
}

DataValue read_dataset(hid_t ds, const std::string& where) {
  H t(H5Dget_type(ds), H5Tclose);
  if (t < 0) throw Error(where + ": cannot read its type");
  H space(H5Dget_space(ds), H5Sclose);
  const hssize_t n = extent(space, where, false);
  check_stored(ds, t, n, where);
  auto read = [&](hid_t mt, void* buf) { return n ? H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) : herr_t{0}; };
  switch (H5Tget_class(t)) {
    case H5T_INTEGER: {
      std::vector<long long> v(n);
      if (read(H5T_NATIVE_LLONG, v.data()) < 0) throw Error(where + ": cannot read it as integers");
      return v;
    }
    case H5T_FLOAT: {
      std::vector<double> v(n);
      if (read(H5T_NATIVE_DOUBLE, v.data()) < 0) throw Error(where + ": cannot read it as numbers");
      return v;
    }
    case H5T_STRING: return read_strings(t, n, where, read);
    default: throw Error(where + ": has an unsupported type (expected integers, floats or strings)");
  }
}

Kind link_kind(hid_t loc, const std::string& name) {
  if (H5Lexists(loc, name.c_str(), H5P_DEFAULT) <= 0) return Kind::missing;  // < 0: a missing parent
  if (H5Oexists_by_name(loc, name.c_str(), H5P_DEFAULT) <= 0) return Kind::dangling;
  H5O_info_t oi;
  if (H5Oget_info_by_name2(loc, name.c_str(), &oi, H5O_INFO_BASIC, H5P_DEFAULT) < 0) return Kind::dangling;
  if (oi.type == H5O_TYPE_GROUP) return Kind::group;
  if (oi.type == H5O_TYPE_DATASET) return Kind::dataset;
  return Kind::other;
}

const char* kind_text(Kind k) {
  switch (k) {
    case Kind::missing: return "missing";
    case Kind::dangling: return "a dangling link (to nothing)";
    case Kind::group: return "a group";
    case Kind::dataset: return "a dataset";
    default: return "neither a group nor a dataset";
  }
}

namespace {
H open_kind(hid_t loc, const std::string& name, const std::string& where, Kind want) {
  const Kind k = link_kind(loc, name);
  const char* what = want == Kind::group ? "a group" : "a dataset";
  if (k != want) throw Error(where + ": " + name + " is " + kind_text(k) + ", expected " + what);
  H id = want == Kind::group ? H(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose)
                             : H(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (id < 0) throw Error(where + ": cannot open " + name);
  return id;
}
}  // namespace

H open_group(hid_t loc, const std::string& name, const std::string& where) { return open_kind(loc, name, where, Kind::group); }
H open_dataset(hid_t loc, const std::string& name, const std::string& where) { return open_kind(loc, name, where, Kind::dataset); }

std::vector<std::string> link_names(hid_t group, const std::string& where) {
  H5G_info_t info;
  if (H5Gget_info(group, &info) < 0) throw Error(where + ": cannot list its members");
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) throw Error(where + ": cannot read the name of member #" + std::to_string(i));
    std::string name(len + 1, '\0');
    H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(), H5P_DEFAULT);
    name.resize(len);
    names.push_back(name);
  }
  return names;
}

namespace {
// Closing the file closes every object still open in it (HDF5's default for its own driver is
// to keep the file open until they are): nothing outlives an H5Fclose.
H file_access() {
  H fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  check_id(fapl, "file access properties");
  check(H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG), "file access properties");
  return fapl;
}

// A name for a file in memory: one that cannot exist on disk (the core driver refuses to open an
// image under the name of an existing file; nothing is ever written under it), and another for
// each file (HDF5 refuses a second file of a name already open: an append holds two at once).
std::string memory_name() {
  static std::atomic<long> count{0};
  return "/dev/null/xpbd-bench-in-memory-" + std::to_string(++count);
}

// The core driver without a backing store: the file lives in memory only.
H memory_access() {
  H fapl = file_access();
  check(H5Pset_fapl_core(fapl, size_t{1} << 20, false), "in-memory file driver");
  return fapl;
}
}  // namespace

H link_create_plist() {
  H lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  check_id(lcpl, "link properties");
  check(H5Pset_create_intermediate_group(lcpl, 1), "link properties");
  return lcpl;
}

H open_file(const std::string& path) {
  silence_errors();
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw Error(path + ": is a directory, not an HDF5 file");
  if (!fs::exists(path, ec)) throw Error(path + ": no such file");
  H f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, file_access()), H5Fclose);
  if (f < 0) throw Error(path + ": not an HDF5 file (or unreadable)");
  return f;
}

H create_memory_file() {
  silence_errors();
  H f(H5Fcreate(memory_name().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, memory_access()), H5Fclose);
  check_id(f, "create a file in memory");
  return f;
}

H open_memory_image(const std::vector<char>& image) {
  silence_errors();
  H fapl = memory_access();
  check(H5Pset_file_image(fapl, const_cast<char*>(image.data()), image.size()), "file image");
  return H(H5Fopen(memory_name().c_str(), H5F_ACC_RDWR, fapl), H5Fclose);
}

std::vector<char> file_image(hid_t file) {
  check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush (in memory)");
  const ssize_t n = H5Fget_file_image(file, nullptr, 0);
  if (n < 0) throw Error("HDF5: file image size failed");
  std::vector<char> image(static_cast<size_t>(n));
  if (H5Fget_file_image(file, image.data(), image.size()) != n) throw Error("HDF5: file image failed");
  return image;
}

void silence_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

}  // namespace xb::h5
