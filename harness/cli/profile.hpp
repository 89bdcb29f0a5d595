// Profiles: a named set of parameter keys (problems/profiles/NAME.toml, same TOML as a scene) that
// `run --profile NAME` applies between the scene and --set (defaults < scene < profile < --set).
// Keys in a [scenes.<builder>] table apply only when the run's scene is that builder, so one
// profile can say "the bunny squash at 0.2 m" without breaking the other scenes.
#pragma once

#include "../params.hpp"

#include <string>
#include <vector>

namespace xb {

// The folder of the built-in profiles (problems/profiles in the source tree, or $XB_PROFILE_DIR).
std::string profile_dir();
std::vector<std::string> profile_names();
// A built-in name or a path to a .toml file → its path; throws xb::Error listing the valid names.
std::string resolve_profile(const std::string& name_or_file);
// Sets the profile's keys in p (after the scene: p.scene is known) and p.profile to its name (the
// file's stem). Errors name the file, line and key.
void apply_profile(const std::string& name_or_file, Params& p);

}  // namespace xb
