// Small HDF5 helpers shared by the recorder and the captured-system files: scoped handles,
// checked calls, and scalar attributes / 1-D datasets of the recorder's value types.
#pragma once

#include "recorder.hpp"

#include <hdf5.h>

#include <string>

namespace xb::h5 {

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

// Throw xb::Error("HDF5: <what> failed") on a negative status or id.
void check(herr_t e, const std::string& what);
void check_id(hid_t id, const std::string& what);
// A variable-length UTF-8 string type (caller closes).
hid_t string_type();
void write_attr(hid_t obj, const std::string& name, const AttrValue& v);
AttrValue read_attr(hid_t attr);
// A 1-D dataset; a '/' in the name creates intermediate groups.
void write_dataset(hid_t group, const std::string& name, const DataValue& v);
DataValue read_dataset(hid_t dataset);
// Turns off HDF5's printing of error stacks (we report our own messages); idempotent.
void silence_errors();

}  // namespace xb::h5
