// Scenes: a TOML spec under problems/scenes/ (or any file) sets parameters; its `scene` key
// names the builder that turns the parameters into a Problem.
#pragma once

#include "meshes/mesh.hpp"
#include "scene_settings.hpp"
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

// The builders by name.
using SceneBuilder = std::function<Problem(const SceneSettings&)>;
struct BuilderInfo {
  std::string name;
  std::string description;
  SceneBuilder build;
};
const std::vector<BuilderInfo>& scene_builders();
// Refuses, by name, a key set to a value the scene's builder would ignore (mesh on cloth_hang, ...).
void check_scene_keys(const SceneSettings& p);
// Whether every constraint of p's scene is compliant (α > 0), from the settings alone: what
// form = auto resolves by (primal when so) before the scene is built.
bool every_constraint_compliant(const SceneSettings& p);
// Builds p.scene's Problem; throws xb::Error for an unknown builder or a broken problem.
Problem build_problem(const SceneSettings& p);

// Extreme cases (the `variant` key; apply_variant_keys in params.hpp sets the keys they imply):
//   rigid            all compliances 0 (infinite stiffness, Goldenthal's method)
//   mu1e12           stiffness 1e12 (heavy_rope, pendulum: link compliance 1e-12 m/N)
//   mass_ratio_1e4   masses graded by index as i² up to a ratio of 1e4 (heavy_rope, pendulum:
//                    the end mass 1e4 times a link particle's)
//   dt_30hz          dt = 1/30 s
//   near_degenerate  tet scenes: flatten_some_tets; cloth: flatten_some_triangles;
//                    mass_chain, heavy_rope, pendulum: every 10th link 1e-3 as long as the others
// apply_variant does the part that acts on a built Problem (rigid; the mass grading of
// mass_ratio, which mass_chain and mass_ratio_1e4 use). build_problem calls it.
void apply_variant(const SceneSettings& p, Problem& prob);
// heavy_rope and pendulum: mass_ratio weighs their last particle only (no i² grading).
bool end_mass_scene(const std::string& scene);
// Every 50th tet flattened to 1e-3 of its height (its last vertex moved towards the opposite
// face) where that inverts no neighbour; the rest shape is this flattened mesh.
void flatten_some_tets(TetMesh& mesh);
// The same for cloth: every 50th triangle flattened to 1e-3 of its height.
void flatten_some_triangles(TriMesh& mesh);

// Shared construction steps.
// Tets: one ARAP constraint per tet, α = 1/(μ V_rest), particle_mass per particle.
Problem make_tet_problem(const std::string& name, const TetMesh& mesh, const SceneSettings& p);
// Cloth: one distance constraint per edge, uniform compliance.
Problem make_cloth_problem(const std::string& name, const TriMesh& mesh, const SceneSettings& p);

}  // namespace xb
