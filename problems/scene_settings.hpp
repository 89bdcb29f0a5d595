// The scene's settings: what is simulated (builder, mesh, material, masses) and for how long.
// Keys are unprefixed ("dt", "mesh"). Units: seconds, kg, m, Pa, m/N.
#pragma once

#include "../core/settings.hpp"

#include <string>

namespace xb {

struct SceneSettings {
  std::string scene = "cloth_hang";  // the scene builder (see problems/scene.cpp)
  std::string mesh = "";             // "" = the builder's generator; "bunny:12k"; or a mesh path
  int resolution = 32;               // cells per side for generated meshes
  int aspect = 4;                    // bar length in cells = aspect * resolution
  double size = 1.0;                 // m: cloth side length / bar cross-section side
  int frames = 1;
  int substeps = 1;                  // substeps per frame
  double dt = 3e-3;                  // s, frame time step (substep = dt / substeps)
  double gravity = -9.8;             // m/s², along y
  double particle_mass = 1.0;        // kg per particle
  double compliance = 1e-8;          // m/N, distance constraints
  double stiffness = 1e6;            // Pa, μ of the tet ARAP constraint (α = 1/(μ V_rest))
  double prestretch = 1.0;           // initial stretch of generated bars along their length (1 = at rest)
  double twist = 0;                  // rad: twist_bar's initial twist of the bar about its long axis, end to end
  double mass_ratio = 1;             // heaviest/lightest particle: mass_i = particle_mass·(1 + (ratio−1)(i/(n−1))²);
                                     // heavy_rope, pendulum: the end particle's mass / a link particle's
  double angle = 0;                  // rad: heavy_rope, pendulum: the chain's initial angle from the downward vertical
  double mesh_height = 0;            // m: mesh scenes scale the mesh so its y extent is this (0 = as the file is)
  std::string init = "none";         // squash start: none (collapsed) | enlarge (rest mesh x1.5 about its centroid)
  std::string variant = "none";      // extreme case (problems/scene.hpp: apply_variant); setting it also sets the keys it implies
  // What a scene file adds to its builder's scene (problems/scene_pins.hpp): pins by particle
  // index and by boxes of the start positions, whether the builder's own pins stay, a ground plane.
  std::string pin_indices;           // "0, 32": particles pinned (inverse mass 0)
  std::string pin_box;               // "xmin, ymin, zmin, xmax, ymax, zmax" (6 numbers per box, m)
  std::string builder_pins = "keep";  // keep | none: the builder's own pins (cloth_hang's corners, ...)
  std::string ground = "builder";    // builder (ball_drop's y = 0, none elsewhere) | none | a height in m
};

const SettingTable<SceneSettings>& scene_settings();

// Sets the keys s.variant implies (rigid: compliance 0; mu1e12: stiffness 1e12;
// mass_ratio_1e4: mass_ratio 1e4; dt_30hz: dt 1/30 s). Called where `variant` is set.
void apply_variant_keys(SceneSettings& s);

// What is wrong with the text of a key that has a format of its own (pins.indices, pins.box,
// ground: problems/scene_pins.cpp); "" when nothing is, or for any other key.
std::string scene_text_error(const std::string& key, const std::string& value);

// Checks across keys, or of defaults a scene file could have left inconsistent (dt > 0, frames >= 1);
// throws xb::Error naming the key.
void validate(const SceneSettings& s);

}  // namespace xb
