// Structure-aware HDF5 inputs (fuzz/README.md): the fuzz bytes pick a file written by the harness
// (fuzz/seeds/TARGET/) and a list of schema-level edits made with the HDF5 C API, so libhdf5
// writes a file that is valid byte for byte but hostile to our reader: wrong kinds, type classes,
// shapes, string sizes and values under the names the reader expects, dangling and wrong links,
// missing members, inconsistent or out-of-range arrays, many runs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace xb_fuzz {

// Builds work_dir()/file from `seed_dir`'s seeds and the edits the bytes decode to; `names` are
// names the reader looks for (tried alongside those already in the file). Returns the path.
// With XB_FUZZ_KEEP=PATH set, the built file is also copied to PATH (a finding's corpus case).
// "" when libhdf5 could not close the edited file (the input is then not read).
std::string build_h5(const std::string& seed_dir, const std::string& file, const std::vector<std::string>& names,
                     const uint8_t* data, size_t size);

// Aborts (a finding) when a reader left any HDF5 object open: the file would stay open.
void expect_no_open_handles();

}  // namespace xb_fuzz
