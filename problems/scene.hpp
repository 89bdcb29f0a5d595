// Scenes: a TOML spec under problems/scenes/ (or any file) sets parameters; its `scene` key
// names the builder that turns the parameters into a Problem.
#pragma once

#include "mesh.hpp"
#include "params.hpp"
#include "problem.hpp"

#include <functional>
#include <string>
#include <vector>

namespace xb {

// The folder of the built-in scene specs (problems/scenes in the source tree, or $XB_SCENE_DIR).
std::string scene_dir();
// Names of the built-in scenes (the .toml files in scene_dir()), sorted.
std::vector<std::string> scene_names();
// A built-in name or a path to a .toml file → the spec's path. Throws xb::Error listing the
// valid names for an unknown one.
std::string resolve_scene(const std::string& name_or_file);

// Reads a TOML spec (nested tables flatten to dotted keys: [amg] strength_threshold → 
// amg.strength_threshold) and sets every key in p. Errors name the file and line.
void load_scene_file(const std::string& path, Params& p);
// Flattened (key, value-as-text, line) triples of a TOML table file; used by scene and sweep specs.
struct TomlEntry {
  std::string key, value;
  int line;
  bool is_array;
  std::vector<std::string> items;  // for arrays
};
std::vector<TomlEntry> read_toml_flat(const std::string& path);

// The builders by name.
using SceneBuilder = std::function<Problem(const Params&)>;
struct BuilderInfo {
  std::string name;
  std::string description;
  SceneBuilder build;
};
const std::vector<BuilderInfo>& scene_builders();
// Builds p.scene's Problem; throws xb::Error for an unknown builder or a broken problem.
Problem build_problem(const Params& p);

// Shared construction steps.
// Tets: one ARAP constraint per tet, α = 1/(μ V_rest), particle_mass per particle.
Problem make_tet_problem(const std::string& name, const TetMesh& mesh, const Params& p);
// Cloth: one distance constraint per edge, uniform compliance.
Problem make_cloth_problem(const std::string& name, const TriMesh& mesh, const Params& p);

}  // namespace xb
