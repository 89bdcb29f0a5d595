// The values, datatypes and dataspaces of the structure-aware HDF5 edits (fuzz/h5_edits.hpp),
// decoded from the fuzz bytes.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>
#include <hdf5.h>

#include <climits>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace xb_fuzz {

inline long long integer(FuzzedDataProvider& in) {
  static const long long table[] = {0, 1, -1, 2, 3, 4, 5, 8, 15, 24, 100, INT_MAX, INT_MAX + 1LL, LLONG_MIN, LLONG_MAX, -2};
  const size_t pick = in.ConsumeIntegralInRange<size_t>(0, std::size(table));
  return pick < std::size(table) ? table[pick] : in.ConsumeIntegral<long long>();
}

inline double number(FuzzedDataProvider& in) {
  const double inf = std::numeric_limits<double>::infinity();
  static const double table[] = {0, 1, -1, 0.5, 1e-300, 1e300, std::nan(""), inf, -inf, 4.9e-324, 2147483648.0, 9.3e18, -0.0};
  const size_t pick = in.ConsumeIntegralInRange<size_t>(0, std::size(table));
  return pick < std::size(table) ? table[pick] : in.ConsumeFloatingPoint<double>();
}

// A datatype of any class the reader may meet (the caller closes it).
inline hid_t make_type(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange(0, 15)) {
    case 0: return H5Tcopy(H5T_NATIVE_LLONG);
    case 1: return H5Tcopy(H5T_STD_I8LE);
    case 2: return H5Tcopy(H5T_STD_U64LE);
    case 3: return H5Tcopy(H5T_STD_I32BE);
    case 4: return H5Tcopy(H5T_IEEE_F32LE);
    case 5: return H5Tcopy(H5T_IEEE_F64BE);
    case 6: {
      const hid_t t = H5Tcopy(H5T_C_S1);
      H5Tset_size(t, in.ConsumeIntegralInRange<size_t>(1, 300));
      H5Tset_strpad(t, in.PickValueInArray({H5T_STR_NULLTERM, H5T_STR_NULLPAD, H5T_STR_SPACEPAD}));
      H5Tset_cset(t, in.ConsumeBool() ? H5T_CSET_UTF8 : H5T_CSET_ASCII);
      return t;
    }
    case 7: {
      const hid_t t = H5Tcopy(H5T_C_S1);
      H5Tset_size(t, H5T_VARIABLE);
      H5Tset_cset(t, in.ConsumeBool() ? H5T_CSET_UTF8 : H5T_CSET_ASCII);
      return t;
    }
    case 8: {
      const hsize_t dims[1] = {in.ConsumeIntegralInRange<hsize_t>(1, 4)};
      return H5Tarray_create2(in.ConsumeBool() ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG, 1, dims);
    }
    case 9: {
      const hid_t t = H5Tcreate(H5T_COMPOUND, 16);
      return H5Tinsert(t, "a", 0, H5T_NATIVE_DOUBLE), H5Tinsert(t, "b", 8, H5T_NATIVE_LLONG), t;
    }
    case 10: {
      const hid_t t = H5Tenum_create(H5T_NATIVE_INT);
      const int values[2] = {0, 1};
      for (int k = 0; k < 2; ++k) H5Tenum_insert(t, k ? "yes" : "no", &values[k]);
      return t;
    }
    case 11: {
      const hid_t t = H5Tcreate(H5T_OPAQUE, in.ConsumeIntegralInRange<size_t>(1, 16));
      H5Tset_tag(t, "fuzz");
      return t;
    }
    case 12: return H5Tcopy(H5T_NATIVE_B8);
    case 13: return H5Tvlen_create(H5T_NATIVE_INT);
    case 14: return H5Tcopy(H5T_STD_REF_OBJ);
    default: return H5Tcopy(H5T_NATIVE_DOUBLE);
  }
}

// A dataspace: scalar, null, 1-D near `hint` elements, 2-D or 3-D; for a dataset also a huge
// declared 1-D extent (`huge`: chunked, never written).
inline hid_t make_space(FuzzedDataProvider& in, bool dataset, hsize_t hint, bool& huge) {
  huge = false;
  switch (in.ConsumeIntegralInRange(0, dataset ? 5 : 4)) {
    case 0: return H5Screate(H5S_SCALAR);
    case 1: return H5Screate(H5S_NULL);
    case 2: {
      const hsize_t choices[] = {0, hint, hint + 1, hint ? hint - 1 : 2, in.ConsumeIntegralInRange<hsize_t>(0, 70)};
      const hsize_t n = in.PickValueInArray(choices);
      return H5Screate_simple(1, &n, nullptr);
    }
    case 3: {
      const hsize_t d[2] = {in.ConsumeIntegralInRange<hsize_t>(0, 5), in.ConsumeIntegralInRange<hsize_t>(0, 5)};
      return H5Screate_simple(2, d, nullptr);
    }
    case 4: {
      const hsize_t d[3] = {1, in.ConsumeIntegralInRange<hsize_t>(1, 3), 1};
      return H5Screate_simple(3, d, nullptr);
    }
    default: {
      huge = true;
      const hsize_t n = hsize_t{1} << in.ConsumeIntegralInRange(20, 40), max = H5S_UNLIMITED;
      return H5Screate_simple(1, &n, &max);
    }
  }
}

// Writes n values of type t through `write(memtype, buffer)` (H5Awrite or H5Dwrite).
template <class Write>
void write_data(FuzzedDataProvider& in, hid_t t, hssize_t n, Write write) {
  if (n <= 0 || n > 4096) return;
  switch (H5Tget_class(t)) {
    case H5T_INTEGER: {
      std::vector<long long> v(n);
      for (auto& x : v) x = integer(in);
      write(H5T_NATIVE_LLONG, v.data());
      return;
    }
    case H5T_FLOAT: {
      std::vector<double> v(n);
      for (auto& x : v) x = number(in);
      write(H5T_NATIVE_DOUBLE, v.data());
      return;
    }
    case H5T_REFERENCE: return;  // left to the fill value: raw bytes are no reference
    case H5T_VLEN: {
      std::vector<int> ints(4, 7);
      std::vector<hvl_t> v(n);
      for (auto& x : v) x = {in.ConsumeIntegralInRange<size_t>(0, 4), ints.data()};
      write(t, v.data());
      return;
    }
    default: break;
  }
  if (H5Tis_variable_str(t) > 0) {
    std::vector<std::string> s(n);
    std::vector<const char*> p;
    for (auto& x : s) p.push_back((x = in.ConsumeRandomLengthString(64)).c_str());
    write(t, p.data());
    return;
  }
  std::vector<uint8_t> raw = in.ConsumeBytes<uint8_t>(H5Tget_size(t) * n);  // strings, arrays, compounds, ...
  raw.resize(H5Tget_size(t) * n, 'x');
  write(t, raw.data());
}

}  // namespace xb_fuzz
