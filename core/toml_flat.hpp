// TOML files as flat (key, value) entries: nested tables flatten to dotted keys
// ([amg] strength_threshold → amg.strength_threshold). Scene specs, profiles and sweep specs use it.
#pragma once

#include <string>
#include <vector>

namespace xb {

// One entry: the key, its value as text (a number in 17 digits, a boolean as 1/0), its line.
struct TomlEntry {
  std::string key, value;
  int line;
  bool is_array;
  std::vector<std::string> items;  // for arrays
};
// The entries of a TOML file, in line order. Errors (a missing file, malformed TOML, an
// unsupported value type) name the file and line.
std::vector<TomlEntry> read_toml_flat(const std::string& path);

}  // namespace xb
