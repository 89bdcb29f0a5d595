// A folder of NAME.toml files under problems/ (scenes, profiles): their names, and a name or a
// path resolved to a file, with one error message for each way it can fail.
#pragma once

#include <string>
#include <vector>

namespace xb {

struct TomlCatalogue {
  std::string what;    // "scene", "profile": used in the messages
  std::string folder;  // under problems/, e.g. "scenes"
  std::string env;     // an environment variable that overrides the folder, e.g. "XB_SCENE_DIR"

  std::string dir() const;
  // The .toml files' stems, sorted.
  std::vector<std::string> names() const;
  // A path (has a '/' or ends in .toml) must exist; a name must be one of names(). Throws
  // xb::Error "<what> file 'X' does not exist" / "unknown <what> 'X' (valid: ...)".
  std::string resolve(const std::string& name_or_file) const;
};

}  // namespace xb
