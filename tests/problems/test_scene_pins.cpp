// A scene file that makes a new scene (problems/scene_pins.hpp): its own pins by index and by box,
// with or without the builder's, checked by which particles end up pinned; a ground plane; and
// bad pins refused with one line naming the key (and the file's line where the text is wrong).
#include "core/error.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

namespace fs = std::filesystem;
using namespace xb;

namespace {
std::string scene_file(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("xb_pins_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return (dir / name).string();
}

std::set<int> pinned(const Problem& prob) {
  std::set<int> s;
  for (int i = 0; i < prob.particles.size(); ++i)
    if (prob.particles.w[i] == 0) s.insert(i);
  return s;
}

std::string error_of(const std::string& file, const std::vector<std::string>& sets = {}) {
  try {
    build_problem(resolve_params(file, sets));
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }
}  // namespace

// cloth_hang at resolution 4: vertex (i, k) is particle 5i + k at (k/4, 0.5, i/4). The file drops
// the builder's two corners (4 and 24), pins 0 and 1 by index and the row i = 2 (z = 0.5) by a box.
TEST(ScenePins, ByIndexAndBoxWithoutTheBuildersPins) {
  const std::string f = scene_file("cloth_row.toml",
                                   "scene = \"cloth_hang\"\nresolution = 4\n[pins]\nbuilder = \"none\"\nindices = [0, 1]\n"
                                   "box = [-0.1, 0.4, 0.45, 1.1, 0.6, 0.55]\n");
  const Problem prob = build_problem(resolve_params(f, {}));
  EXPECT_EQ(pinned(prob), (std::set<int>{0, 1, 10, 11, 12, 13, 14}));
  // Kept, the builder's corners join them; two boxes in one list pin both rows.
  const Problem kept = build_problem(resolve_params(f, {"pins.builder=keep", "pins.box=-1, 0, -0.01, 2, 1, 0.01, -1, 0, 0.99, 2, 1, 1.01"}));
  EXPECT_EQ(pinned(kept), (std::set<int>{0, 1, 2, 3, 4, 20, 21, 22, 23, 24}));
}

// The example of docs/commands.md ("Scene files"): a cloth hanging from one edge and a corner.
TEST(ScenePins, TheDocsExample) {
  const std::string f = scene_file("edge.toml",
                                   "scene = \"cloth_hang\"\nresolution = 16\n[pins]\nbuilder = \"none\"\n"
                                   "box = [-1, 0, -0.01, 2, 1, 0.01]\nindices = [272]\n");
  std::set<int> expected{272};
  for (int k = 0; k <= 16; ++k) expected.insert(k);
  EXPECT_EQ(pinned(build_problem(resolve_params(f, {}))), expected);
}

// A tet bar pinned at its far end instead of bar_hang's x = 0 end: the pinned particles are those
// at the largest x, and they do not move in a run while the rest of the bar falls. The file starts
// from the defaults (size 1 m, aspect 4): at resolution 2 the bar is 8 cells of 0.5 m along x.
TEST(ScenePins, ABoxPinsATetBarAtItsOtherEndAndHoldsInARun) {
  const std::string f = scene_file("bar_far.toml",
                                   "scene = \"bar_hang\"\nresolution = 2\nframes = 3\nmax_iterations = 20\n"
                                   "pins.builder = \"none\"\npins.box = [0.7, -1, -1, 0.8, 2, 2]\n");
  // The file's box lies between two layers of nodes (x = 0.5 and 1): it holds none, an error.
  EXPECT_TRUE(has(error_of(f), "box 1 holds no particle of scene 'bar_hang' at its start (x in [0, 4]")) << error_of(f);
  const Params q = resolve_params(f, {"pins.box=3.9, -1, -1, 4.1, 2, 2"});
  const Problem bar = build_problem(q);
  std::set<int> far;
  for (int i = 0; i < bar.particles.size(); ++i)
    if (bar.particles.x(0, i) == 4.0) far.insert(i);
  ASSERT_EQ(far.size(), 9u);  // a 3 x 3 face of nodes
  EXPECT_EQ(pinned(bar), far);
  const RunResult r = run_simulation(bar, q, "cholmod", {});
  ASSERT_NE(r.status, "error") << r.message;
  for (int i = 0; i < bar.particles.size(); ++i) {
    if (far.count(i)) EXPECT_EQ(r.final_positions.col(i), bar.particles.x.col(i)) << i;
    else EXPECT_LT(r.final_positions(1, i), bar.particles.x(1, i)) << i;  // the rest hangs under gravity
  }
}

TEST(ScenePins, BadPinsNameTheKeyAndLine) {
  const std::string out_of_range = scene_file("far.toml", "scene = \"cloth_hang\"\nresolution = 4\npins.indices = [0, 25]\n");
  EXPECT_TRUE(has(error_of(out_of_range), "parameter 'pins.indices' = '0, 25': particle 25 is out of range (scene 'cloth_hang' has 25 particles"));
  const std::string negative = scene_file("neg.toml", "scene = \"cloth_hang\"\npins.indices = [3, -1]\n");
  EXPECT_TRUE(has(error_of(negative), "neg.toml:2: parameter 'pins.indices' = '3, -1': '-1' is not a particle index")) << error_of(negative);
  const std::string word = scene_file("word.toml", "scene = \"cloth_hang\"\n[pins]\nindices = [\"a\"]\n");
  EXPECT_TRUE(has(error_of(word), "word.toml:3: parameter 'pins.indices' = 'a': 'a' is not a finite number")) << error_of(word);
  const std::string short_box = scene_file("short.toml", "scene = \"cloth_hang\"\npins.box = [0, 0, 0]\n");
  EXPECT_TRUE(has(error_of(short_box), "short.toml:2: parameter 'pins.box' = '0, 0, 0': 3 numbers: a box is 6")) << error_of(short_box);
  const std::string flipped = scene_file("flipped.toml", "scene = \"cloth_hang\"\npins.box = [1, 0, 0, 0, 1, 1]\n");
  EXPECT_TRUE(has(error_of(flipped), "flipped.toml:2: parameter 'pins.box'") && has(error_of(flipped), "minimum above its maximum"));
  const std::string empty = scene_file("empty.toml", "scene = \"cloth_hang\"\nresolution = 4\npins.box = [5, 5, 5, 6, 6, 6]\n");
  EXPECT_TRUE(has(error_of(empty), "parameter 'pins.box' = '5, 5, 5, 6, 6, 6': box 1 holds no particle of scene 'cloth_hang'")) << error_of(empty);
  const std::string list = scene_file("list.toml", "scene = \"cloth_hang\"\nresolution = [4, 8]\n");
  EXPECT_TRUE(has(error_of(list), "list.toml:2: 'resolution' must be a single value, not a list")) << error_of(list);
  EXPECT_TRUE(has(error_of("cloth_hang", {"pins.indices=0;1"}), "--set: parameter 'pins.indices' = '0;1'")) << error_of("cloth_hang", {"pins.indices=0;1"});
  EXPECT_TRUE(has(error_of("cloth_hang", {"ground=low"}), "--set: parameter 'ground' = 'low': 'low' is not a finite number"));
}

// ground: a plane under the cloth catches it; "none" lets ball_drop's ball fall through y = 0.
TEST(ScenePins, GroundPlaneFromTheSceneFile) {
  const Params cloth = resolve_params("cloth_hang", {"resolution=4", "frames=10", "dt=0.02", "ground=0.45", "max_iterations=20"});
  const Problem prob = build_problem(cloth);
  ASSERT_EQ(prob.planes.size(), 1u);
  const RunResult r = run_simulation(prob, cloth, "cholmod", {});
  ASSERT_NE(r.status, "error") << r.message;
  EXPECT_GE(r.final_positions.row(1).minCoeff(), 0.45 - 1e-12);
  EXPECT_LT(r.final_positions.row(1).minCoeff(), 0.46);  // it reached the plane
  EXPECT_TRUE(build_problem(resolve_params("ball_drop", {"ground=none"})).planes.empty());
  EXPECT_EQ(build_problem(resolve_params("ball_drop", {})).planes.size(), 1u);
}
