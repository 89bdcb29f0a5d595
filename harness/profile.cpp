#include "profile.hpp"

#include "../problems/error.hpp"
#include "../problems/scene.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#ifndef XB_SOURCE_DIR
#define XB_SOURCE_DIR "."
#endif

namespace fs = std::filesystem;

namespace xb {

std::string profile_dir() {
  if (const char* d = std::getenv("XB_PROFILE_DIR")) return d;
  return std::string(XB_SOURCE_DIR) + "/problems/profiles";
}

std::vector<std::string> profile_names() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(profile_dir(), ec))
    if (e.path().extension() == ".toml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string resolve_profile(const std::string& name_or_file) {
  if (name_or_file.find('/') != std::string::npos || name_or_file.ends_with(".toml")) {
    if (!fs::is_regular_file(name_or_file)) throw Error("--profile: file '" + name_or_file + "' does not exist");
    return name_or_file;
  }
  const auto names = profile_names();
  if (std::find(names.begin(), names.end(), name_or_file) == names.end()) {
    std::string valid;
    for (const auto& n : names) valid += (valid.empty() ? "" : ", ") + n;
    throw Error("--profile: unknown profile '" + name_or_file + "' (valid: " + valid + ")");
  }
  return profile_dir() + "/" + name_or_file + ".toml";
}

void apply_profile(const std::string& name_or_file, Params& p) {
  const std::string path = resolve_profile(name_or_file);
  const std::string scene_prefix = "scenes.";
  for (auto e : read_toml_flat(path)) {
    const std::string where = path + ":" + std::to_string(e.line);
    if (e.is_array) throw Error(where + ": '" + e.key + "' must be a single value, not a list");
    if (e.key.rfind(scene_prefix, 0) == 0) {
      // [scenes.<builder>] key = value: only for that scene.
      const std::string rest = e.key.substr(scene_prefix.size());
      const auto dot = rest.find('.');
      if (dot == std::string::npos) throw Error(where + ": '" + e.key + "': expected [scenes.<builder>] key = value");
      if (rest.substr(0, dot) != p.scene) continue;
      e.key = rest.substr(dot + 1);
    }
    if (e.key == "scene" || e.key == "variant")
      throw Error(where + ": a profile may not set '" + e.key + "' (it chooses how a scene is run, not which)");
    set_param(p, e.key, e.value, where);
  }
  p.profile = fs::path(path).stem().string();
}

}  // namespace xb
