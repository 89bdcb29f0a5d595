// The one flat key space users see: the scene's settings, the stepper's and every solver's,
// composed from the tables each component owns (problems/scene_settings.hpp,
// harness/stepper_settings.hpp, solvers/solver_settings.hpp). Defaults, scene and profile
// TOML, --set key=value, sweeps and the HDF5 attributes of a run all go through param_fields(),
// so a key is spelled the same everywhere.
#pragma once

#include "../problems/scene_settings.hpp"
#include "../solvers/solver_settings.hpp"
#include "stepper_settings.hpp"

#include <string>

namespace xb {

struct Params : SceneSettings, StepperSettings, SolverSettings {
  // The profile the parameters came from ("" = none; harness/cli/profile.hpp). Not a key (a
  // profile is a set of keys, not one): simulation runs record it as the attribute `profile`.
  std::string profile;
};

using ParamField = SettingField<Params>;
using ParamValue = SettingValue;
const SettingTable<Params>& param_fields();
const ParamField* find_param(const std::string& key);

// Sets one key from text, validating type, bounds and choices; setting `variant` also sets the
// keys it implies. `where` names the source ("--set", "scene.toml:12"). Throws xb::Error.
void set_param(Params& p, const std::string& key, const std::string& value, const std::string& where);
// Every key of a TOML file (a scene spec): errors name the file and line.
void load_scene_file(const std::string& path, Params& p);

// A key's value as text (for tables, JSON, the MPI workers) and typed (for HDF5).
std::string param_to_string(const Params& p, const ParamField& f);
ParamValue param_value(const Params& p, const ParamField& f);

// Cross-field checks (e.g. dt > 0); throws xb::Error naming the key.
void validate(const Params& p);

}  // namespace xb
