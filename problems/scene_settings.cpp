#include "scene_settings.hpp"

#include "../core/error.hpp"

namespace xb {

const SettingTable<SceneSettings>& scene_settings() {
  using S = SceneSettings;
  constexpr double inf = 1e300;
  static const SettingTable<S> table = {
      setting("scene", "scene builder name", &S::scene),
      setting("mesh", "mesh: '' (generator), 'bunny:12k', or a .msh/.mesh/.ele/.node path", &S::mesh),
      setting("resolution", "cells per side of generated meshes", &S::resolution, 1, 4096),
      setting("aspect", "bar length in cells = aspect * resolution", &S::aspect, 1, 1024),
      setting("size", "m, cloth side / bar cross-section side", &S::size, 1e-6, inf),
      setting("frames", "frames to simulate", &S::frames, 1, 1e9),
      setting("substeps", "substeps per frame", &S::substeps, 1, 1e6),
      setting("dt", "s, frame time step", &S::dt, 1e-300, inf),
      setting("gravity", "m/s^2 along y", &S::gravity),
      setting("particle_mass", "kg per particle", &S::particle_mass, 1e-300, inf),
      setting("compliance", "m/N, distance-constraint compliance (0 = rigid)", &S::compliance, 0, inf),
      setting("stiffness", "Pa, ARAP shear modulus mu of tets (alpha = 1/(mu V))", &S::stiffness, 1e-300, inf),
      setting("prestretch", "initial stretch of a generated bar along its length (1 = rest shape)", &S::prestretch, 0.1, 10),
      setting("twist", "rad, twist_bar: initial twist about the long axis, end to end", &S::twist, -1e3, 1e3),
      setting("mass_ratio", "heaviest/lightest particle mass, graded by index as i^2 (1 = uniform); heavy_rope, pendulum: the end mass over a link particle's", &S::mass_ratio, 1, 1e300),
      setting("angle", "rad, heavy_rope and pendulum: the chain's initial angle from the downward vertical", &S::angle, -10, 10),
      setting("mesh_height", "m, mesh scenes (squash, twist_bar, cantilever, ball_drop): scale the mesh uniformly so its y extent is this (0 = as the mesh is)", &S::mesh_height, 0, inf),
      setting("init", "squash's start: none (collapsed to min y) | enlarge (the rest mesh x1.5 about its centroid, the authors' enlarge start)", &S::init, {"none", "enlarge"}),
      setting("variant", "extreme case: none | rigid | mu1e12 | mass_ratio_1e4 | dt_30hz | near_degenerate (sets the keys it implies)", &S::variant, {"none", "rigid", "mu1e12", "mass_ratio_1e4", "dt_30hz", "near_degenerate"}),
  };
  return table;
}

void apply_variant_keys(SceneSettings& s) {
  // What each extreme case changes in the parameters; rigid and near_degenerate also act on the
  // built Problem (problems/scene.cpp: apply_variant_to_problem / the mesh builders).
  if (s.variant == "rigid") s.compliance = 0;
  else if (s.variant == "mu1e12") s.stiffness = 1e12;
  else if (s.variant == "mass_ratio_1e4") s.mass_ratio = 1e4;
  else if (s.variant == "dt_30hz") s.dt = 1.0 / 30.0;
}

void validate(const SceneSettings& s) {
  if (!(s.dt > 0)) throw Error("parameter 'dt' must be > 0");
  if (s.frames < 1) throw Error("parameter 'frames' must be >= 1");
}

}  // namespace xb
