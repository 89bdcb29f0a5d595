// Small HDF5 helpers shared by the recorder and the captured-system files: scoped handles,
// checked calls, and scalar attributes / 1-D datasets of the recorder's value types.
#pragma once

#include "h5handle.hpp"
#include "record.hpp"

#include <hdf5.h>

#include <map>
#include <string>
#include <vector>

namespace xb::h5 {

// Throw xb::Error("HDF5: <what> failed") on a negative status or id.
void check(herr_t e, const std::string& what);
void check_id(hid_t id, const std::string& what);
// A variable-length UTF-8 string type.
H string_type();
void write_attr(hid_t obj, const std::string& name, const AttrValue& v);
// Link creation properties that create missing intermediate groups.
H link_create_plist();
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
H open_group(hid_t loc, const std::string& name, const std::string& where);
H open_dataset(hid_t loc, const std::string& name, const std::string& where);
// The names of a group's links, in name order.
std::vector<std::string> link_names(hid_t group, const std::string& where);
// An HDF5 file opened read-only, or "<path>: no such file / is a directory / not an HDF5 file".
H open_file(const std::string& path);

// Files we write are built in memory (HDF5's core driver, no backing store) and their image
// written through the atomic layer (atomic_file.hpp) by us: HDF5 itself never writes to disk, so
// a full disk cannot leave an HDF5 file half-written and half-closed inside the library (the
// crash of issue 33 in its exit handlers), and every failed write is met in one place, with its
// errno, where the test hook (io_fault.hpp) can fail it too. The cost is the file's size in
// memory, twice while its image is taken; results and captured systems are MBs, not GBs.
// Each file closes strongly: closing it closes every object still open in it.
H create_memory_file();
// A file in memory, writable, holding a copy of `image` (a file's bytes); an invalid id (< 0) when
// they are not an HDF5 file.
H open_memory_image(const std::vector<char>& image);
// The bytes of a file built in memory, flushed first.
std::vector<char> file_image(hid_t file);
// Turns off HDF5's printing of error stacks (we report our own messages); idempotent.
void silence_errors();

}  // namespace xb::h5
