// capture_system (harness/sim/capture.hpp) writes XPBD's linear step only: under step = newton
// or a non-default xpbd.geometric_stiffness / xpbd.primal_residual the run solves another system,
// so it refuses with one message naming the key, before it runs or writes anything.
#include "harness/cli/commands.hpp"
#include "harness/cli/profile.hpp"
#include "harness/sim/capture.hpp"
#include "core/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using namespace xb;
using namespace xb::test;

namespace {
Params twist_bar() {
  Params p;
  load_scene_file(std::string(XB_SOURCE_DIR) + "/problems/scenes/twist_bar.toml", p);
  p.resolution = 2;
  return p;
}
}  // namespace

TEST(Capture, RefusesWhatItWouldNotWriteTruly) {
  Params newton = twist_bar();
  apply_profile("newton", newton);
  Params diagonal = twist_bar();
  diagonal.geometric_stiffness = "diagonal";
  Params keep = twist_bar();
  keep.primal_residual = "keep";
  const std::pair<Params, std::string> cases[] = {
      {newton, "step=newton"}, {diagonal, "xpbd.geometric_stiffness=diagonal"}, {keep, "xpbd.primal_residual=keep"}};
  for (const auto& [p, key] : cases) {
    try {
      capture_system(p, "cholmod", 0, 0, 1);
      ADD_FAILURE() << "captured under " << key;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("capture: " + key + " solves a system other than XPBD's", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  // XPBD's own step (the defaults, and the line search, which changes only the step's length) is captured.
  Params line_search = twist_bar();
  line_search.step = "line_search";
  EXPECT_GT(capture_system(twist_bar(), "cholmod", 0, 0, 1).A.rows(), 0);
  EXPECT_GT(capture_system(line_search, "cholmod", 0, 0, 1).A.rows(), 0);
}

// Through the command: an error naming the key and no file.
TEST(Capture, CommandRefusesNewtonAndWritesNothing) {
  TempDir dir;
  const std::string prefix = dir / "sys";
  try {
    cmd_capture({"--scene", "twist_bar", "--set", "resolution=2", "--set", "step=newton", "--set",
                 "xpbd.primal_residual=keep", "--set", "xpbd.geometric_stiffness=full", "--set", "form=primal", "--frame",
                 "0", "--iteration", "1", "--out", prefix});
    ADD_FAILURE() << "capture ran under step=newton";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("step=newton"), std::string::npos) << e.what();
  }
  for (const char* f : {".h5", "_A.mtx", "_b.mtx", "_K.mtx", "_f.mtx"})
    EXPECT_FALSE(std::filesystem::exists(prefix + f)) << f;
}
