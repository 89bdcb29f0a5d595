// The one flat key space users see: the scene's settings, the stepper's and every solver's,
// composed from the tables each component owns (problems/scene_settings.hpp,
// harness/stepper_settings.hpp, solvers/solver_settings.hpp). Defaults, scene and profile
// TOML, --set key=value, sweeps and the HDF5 attributes of a run all go through param_fields(),
// so a key is spelled the same everywhere.
#pragma once

#include "../problems/scene_settings.hpp"
#include "../solvers/solver_settings.hpp"
#include "stepper_settings.hpp"
#include "../core/toml_flat.hpp"

#include <map>
#include <string>

namespace xb {

// Who set a key: the command (--set, --variant, --frames, a sweep's [set] and [grid]), a file
// (the scene file, a profile), or nobody the key check asks about (a captured system's attributes).
enum class KeySource { command, file, none };

struct Params : SceneSettings, StepperSettings, SolverSettings {
  // The profile the parameters came from ("" = none; harness/cli/profile.hpp). Not a key (a
  // profile is a set of keys, not one): simulation runs record it as the attribute `profile`.
  std::string profile;
  // Where each key was set (its `where`, e.g. "--set", "squash.toml:12"), by the command and by a
  // file: what harness/key_check.hpp refuses when it would change nothing.
  std::map<std::string, std::string> set_by_command, set_in_file;
};

using ParamField = SettingField<Params>;
using ParamValue = SettingValue;
const SettingTable<Params>& param_fields();
const ParamField* find_param(const std::string& key);

// Sets one key from text, validating type, bounds and choices; setting `variant` also sets the
// keys it implies. `where` names the source ("--set", "scene.toml:12"), `source` who set it.
// Throws xb::Error.
void set_param(Params& p, const std::string& key, const std::string& value, const std::string& where,
               KeySource source = KeySource::command);
// Every key of a TOML file (a scene spec): errors name the file and line.
void load_scene_file(const std::string& path, Params& p);
// A file entry's value as set_param takes it: a TOML list only for a list key (pins.indices,
// pins.box: joined with ", "), refused for any other key.
std::string entry_value(const TomlEntry& e, const std::string& where);

// A key's value as text (for tables, JSON, the MPI workers) and typed (for HDF5).
std::string param_to_string(const Params& p, const ParamField& f);
ParamValue param_value(const Params& p, const ParamField& f);

// Cross-field checks (e.g. dt > 0); throws xb::Error naming the key.
void validate(const Params& p);

}  // namespace xb
