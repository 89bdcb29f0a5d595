#include "params.hpp"

#include "../core/error.hpp"
#include "../core/toml_flat.hpp"

#include <algorithm>

namespace xb {

namespace {
SettingTable<Params> make_table() {
  SettingTable<Params> t;
  append_part(t, scene_settings(), [](Params& p) -> SceneSettings& { return p; });
  append_part(t, stepper_settings(), [](Params& p) -> StepperSettings& { return p; });
  append_part(t, solver_settings(), [](Params& p) -> SolverSettings& { return p; });
  return t;
}
}  // namespace

const SettingTable<Params>& param_fields() {
  static const SettingTable<Params> table = make_table();
  return table;
}

const ParamField* find_param(const std::string& key) { return find_setting(param_fields(), key); }

void set_param(Params& p, const std::string& key, const std::string& value, const std::string& where, KeySource source) {
  if (const std::string why = scene_text_error(key, value); !why.empty())
    throw Error(where + ": parameter '" + key + "' = '" + value + "': " + why);
  set_setting(param_fields(), p, key, value, where);
  if (source == KeySource::command) p.set_by_command[key] = where;
  if (source == KeySource::file) p.set_in_file[key] = where;
  if (key == "variant") apply_variant_keys(p);  // a variant sets the keys it implies, where it is set
}

void load_scene_file(const std::string& path, Params& p) {
  const auto entries = read_toml_flat(path);
  // Without `scene` the default builder would run silently, whatever the file meant.
  if (std::none_of(entries.begin(), entries.end(), [](const TomlEntry& e) { return e.key == "scene"; }))
    throw Error(path + ": " + (entries.empty() ? "empty scene file" : "no 'scene' key") +
                " (a scene file names its builder: scene = \"cloth_hang\", ...)");
  for (const auto& e : entries) {
    const std::string where = path + ":" + std::to_string(e.line);
    set_param(p, e.key, entry_value(e, where), where, KeySource::file);
  }
}

std::string entry_value(const TomlEntry& e, const std::string& where) {
  if (!e.is_array) return e.value;
  const ParamField* f = find_param(e.key);
  if (!f || !f->list) throw Error(where + ": '" + e.key + "' must be a single value, not a list");
  std::string joined;
  for (const auto& item : e.items) joined += (joined.empty() ? "" : ", ") + item;
  return joined;
}

std::string param_to_string(const Params& p, const ParamField& f) { return setting_text(f, p); }
ParamValue param_value(const Params& p, const ParamField& f) { return setting_value(f, p); }

void validate(const Params& p) {
  // Bounds are checked per key in set_param; these are the checks across keys or of defaults
  // that a scene file could have left inconsistent.
  validate(static_cast<const SceneSettings&>(p));
  if (p.max_iterations < 1) throw Error("parameter 'max_iterations' must be >= 1");
}

}  // namespace xb
