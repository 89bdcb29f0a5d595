// What a scene file adds to the scene its builder makes: pins and a ground plane, so that a scene
// file can make a new scene from a builder's geometry (docs/commands.md, "Scene files").
//   pins.indices = [0, 32]                      particles pinned by index
//   pins.box = [-1, 0.4, -1, 0, 0.6, 1]          every particle whose start position is in the box
//                                               (xmin, ymin, zmin, xmax, ymax, zmax; several boxes:
//                                               6 numbers each, in one list)
//   pins.builder = "none"                       drop the builder's own pins (cloth_hang's corners, ...)
//   ground = 0.0                                a plane y = 0 (particles below it are projected
//                                               onto it); "none" removes ball_drop's
// The start positions are those the builder made (squash: collapsed; twist_bar: twisted).
#pragma once

#include "problem.hpp"
#include "scene_settings.hpp"

#include <string>
#include <vector>

namespace xb {

// The numbers of a list key's text ("0, 32" or "0 32"); throws xb::Error saying what is wrong.
std::vector<double> list_numbers(const std::string& key, const std::string& text);

// Applies pins.builder, pins.indices, pins.box and ground to a built problem, before the mass
// grading of apply_variant (pins stay pinned). Throws xb::Error naming the key for an index out of
// range or a box that holds no particle (a pin that pins nothing is a mistake, not a no-op).
void apply_pins_and_ground(const SceneSettings& p, Problem& prob);

}  // namespace xb
