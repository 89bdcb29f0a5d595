#include "profile.hpp"

#include "../../core/error.hpp"
#include "../../core/toml_flat.hpp"
#include "../../problems/scene.hpp"
#include "../../problems/toml_catalogue.hpp"

#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

namespace {
const TomlCatalogue profiles{"profile", "profiles", "XB_PROFILE_DIR"};
}  // namespace

std::string profile_dir() { return profiles.dir(); }
std::vector<std::string> profile_names() { return profiles.names(); }

std::string resolve_profile(const std::string& name_or_file) {
  try {
    return profiles.resolve(name_or_file);
  } catch (const Error& e) {
    throw Error(std::string("--profile: ") + e.what());
  }
}

void apply_profile(const std::string& name_or_file, Params& p) {
  const std::string path = resolve_profile(name_or_file);
  const std::string scene_prefix = "scenes.";
  for (auto e : read_toml_flat(path)) {
    const std::string where = path + ":" + std::to_string(e.line);
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
    set_param(p, e.key, entry_value(e, where), where, KeySource::file);
  }
  p.profile = fs::path(path).stem().string();
}

}  // namespace xb
