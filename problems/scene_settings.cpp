#include "scene_settings.hpp"

#include "../core/error.hpp"

namespace xb {

const SettingTable<SceneSettings>& scene_settings() {
  using S = SceneSettings;
  constexpr double inf = 1e300;
  // Where each key is read (core/key_scope.hpp): the builders, and the mesh generators of the
  // mesh scenes (mesh = bar | ball, or none: the scene's own generator).
  const std::string distance = "scene=cloth_hang|mass_chain|heavy_rope|pendulum";
  const std::string tets = "scene=bar_hang|squash|twist_bar|cantilever|ball_drop";
  const std::string mesh_scenes = "scene=squash|twist_bar|cantilever|ball_drop";
  const std::string own_geometry = "scene=cloth_hang|bar_hang|mass_chain|heavy_rope|pendulum";
  static const SettingTable<S> table = {
      setting("scene", "scene builder name", &S::scene).applies({on("")}),
      setting("mesh", "mesh: '' (generator), 'bunny:12k', or a .msh/.mesh/.ele/.node path", &S::mesh).applies({on("").where(mesh_scenes)}),
      setting("resolution", "cells per side of generated meshes", &S::resolution, 1, 4096)
          .applies({on("").where(own_geometry), on("").where(mesh_scenes).where("mesh=|bar|ball")}),
      setting("aspect", "bar length in cells = aspect * resolution", &S::aspect, 1, 1024)
          .applies({on("").where("scene=bar_hang"), on("").where(mesh_scenes).where("mesh=bar"),
                    on("").where("scene=twist_bar|cantilever").where("mesh=")}),
      setting("size", "m, cloth side / bar cross-section side", &S::size, 1e-6, inf)
          .applies({on("").where(own_geometry), on("").where(mesh_scenes).where("mesh=|bar|ball")}),
      setting("frames", "frames to simulate", &S::frames, 1, 1e9).applies({on("")}),
      setting("substeps", "substeps per frame", &S::substeps, 1, 1e6).applies({on("")}),
      setting("dt", "s, frame time step", &S::dt, 1e-300, inf).applies({on("")}),
      setting("gravity", "m/s^2 along y", &S::gravity).applies({on("")}),
      setting("particle_mass", "kg per particle", &S::particle_mass, 1e-300, inf).applies({on("")}),
      setting("compliance", "m/N, distance-constraint compliance (0 = rigid)", &S::compliance, 0, inf)
          .applies({on("").where("scene=cloth_hang|mass_chain").where("variant!=rigid"),
                    on("").where("scene=heavy_rope|pendulum").where("variant!=rigid|mu1e12")})
          .instead(on("").where(tets), "stiffness"),
      setting("stiffness", "Pa, ARAP shear modulus mu of tets (alpha = 1/(mu V))", &S::stiffness, 1e-300, inf)
          .applies({on("").where(tets).where("variant!=rigid")})
          .instead(on("").where(distance), "compliance"),
      setting("prestretch", "initial stretch of a generated bar along its length (1 = rest shape)", &S::prestretch, 0.1, 10)
          .applies({on("").where("scene=bar_hang")}),
      setting("twist", "rad, twist_bar: initial twist about the long axis, end to end", &S::twist, -1e3, 1e3)
          .applies({on("").where("scene=twist_bar")}),
      setting("mass_ratio", "heaviest/lightest particle mass, graded by index as i^2 (1 = uniform); heavy_rope, pendulum: the end mass over a link particle's", &S::mass_ratio, 1, 1e300)
          .applies({on("")}),
      setting("angle", "rad, heavy_rope and pendulum: the chain's initial angle from the downward vertical", &S::angle, -10, 10)
          .applies({on("").where("scene=heavy_rope|pendulum")}),
      setting("mesh_height", "m, mesh scenes (squash, twist_bar, cantilever, ball_drop): scale the mesh uniformly so its y extent is this (0 = as the mesh is)", &S::mesh_height, 0, inf)
          .applies({on("").where(mesh_scenes)}),
      setting("init", "squash's start: none (collapsed to min y) | enlarge (the rest mesh x1.5 about its centroid, the authors' enlarge start)", &S::init, {"none", "enlarge"})
          .applies({on("").where("scene=squash")}),
      setting("variant", "extreme case: none | rigid | mu1e12 | mass_ratio_1e4 | dt_30hz | near_degenerate (sets the keys it implies)", &S::variant, {"none", "rigid", "mu1e12", "mass_ratio_1e4", "dt_30hz", "near_degenerate"})
          .applies({on("").where("variant!=mu1e12"), on("").where("variant=mu1e12").where(tets),
                    on("").where("variant=mu1e12").where("scene=heavy_rope|pendulum")})
          .instead(on("").where("scene=cloth_hang|mass_chain"), "compliance"),
      setting("pins.indices", "particles pinned (inverse mass 0) by index, e.g. [0, 32] in a scene file or \"0, 32\" with --set", &S::pin_indices)
          .applies({on("")}).list_value(),
      setting("pins.box", "particles pinned by their start position: every particle in the box xmin, ymin, zmin, xmax, ymax, zmax (m; 6 numbers per box, several boxes in one list)", &S::pin_box)
          .applies({on("")}).list_value(),
      setting("pins.builder", "the builder's own pins (cloth_hang: two corners; bar_hang: the x = 0 end; cantilever: the left 1%; the chains: the first particle): keep | none", &S::builder_pins, {"keep", "none"})
          .applies({on("").where("scene=cloth_hang|bar_hang|cantilever|mass_chain|heavy_rope|pendulum")}),
      setting("ground", "a ground plane y = h (particles below it are projected onto it): builder (ball_drop's y = 0; none elsewhere) | none | h in m", &S::ground)
          .applies({on("").where("ground!=none"), on("").where("scene=ball_drop")}),
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
  for (const auto& [key, value] : {std::pair<const char*, const std::string&>{"pins.indices", s.pin_indices},
                                   {"pins.box", s.pin_box}, {"ground", s.ground}})
    if (const std::string why = scene_text_error(key, value); !why.empty())
      throw Error(std::string("parameter '") + key + "' = '" + value + "': " + why);
  if (s.frames < 1) throw Error("parameter 'frames' must be >= 1");
}

}  // namespace xb
