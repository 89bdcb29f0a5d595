// What the tests of harness/sim share: a stock scene's parameters as `run --scene NAME` reads them,
// and the same under `--profile newton`.
#pragma once

#include "harness/cli/profile.hpp"
#include "harness/params.hpp"

#include <string>

namespace xb::test {

inline Params scene_params(const std::string& scene) {
  Params p;
  load_scene_file(std::string(XB_SOURCE_DIR) + "/problems/scenes/" + scene + ".toml", p);
  return p;
}

inline Params newton_params(const std::string& scene) {
  Params p = scene_params(scene);
  apply_profile("newton", p);
  return p;
}

}  // namespace xb::test
