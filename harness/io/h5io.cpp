#include "h5io.hpp"

#include "../../core/error.hpp"

#include <vector>

namespace xb::h5 {

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

void silence_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

}  // namespace xb::h5
