// Small HDF5 helpers shared by the recorder and the captured-system files: scoped handles,
// checked calls, and scalar attributes / 1-D datasets of the recorder's value types.
#pragma once

#include "record.hpp"

#include <hdf5.h>

#include <map>
#include <string>
#include <vector>

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
// A 1-D dataset; a '/' in the name creates intermediate groups.
void write_dataset(hid_t group, const std::string& name, const DataValue& v);

// Readers: each checks the call's result, the object's kind, its shape and its string size
// before touching memory, and throws xb::Error starting with `where` (the file and the object).
// A scalar (or one-element) integer, float or string attribute (fixed or variable length).
AttrValue read_attr(hid_t attr, const std::string& where);
// Every attribute of an object, by name.
std::map<std::string, AttrValue> read_attrs(hid_t obj, const std::string& where);
// A 1-D integer, float or string dataset.
DataValue read_dataset(hid_t dataset, const std::string& where);
// What a name under `loc` is: a dangling link is a soft or external link to nothing.
enum class Kind { missing, dangling, group, dataset, other };
Kind link_kind(hid_t loc, const std::string& name);
const char* kind_text(Kind k);
// Opens `name` under `loc` when it is a group (a dataset); else throws "<where>: <name> is ...".
hid_t open_group(hid_t loc, const std::string& name, const std::string& where);
hid_t open_dataset(hid_t loc, const std::string& name, const std::string& where);
// The names of a group's links, in name order.
std::vector<std::string> link_names(hid_t group, const std::string& where);
// An HDF5 file opened read-only, or "<path>: no such file / is a directory / not an HDF5 file".
hid_t open_file(const std::string& path);
// Turns off HDF5's printing of error stacks (we report our own messages); idempotent.
void silence_errors();

}  // namespace xb::h5
