// Inputs are never outputs, one test per rule: no command writes over a file it reads (compared by
// identity, not spelling), capture never replaces a results file, run and solve replace only
// results files, output folders are checked before the first run, .tmp files never outlive a
// failure; and a results file with unreadable runs is read run by run.
#include "harness/cli/commands.hpp"
#include "harness/io/atomic_file.hpp"
#include "harness/io/recorder.hpp"
#include "core/error.hpp"
#include "../../test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace xb;
using namespace xb::test;
namespace fs = std::filesystem;

namespace {
std::string slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
void write(const std::string& p, const std::string& text) { std::ofstream(p) << text; }

// The command fails with `fragment` in its message and every file in `kept` is byte-identical.
template <class Cmd>
void expect_refused(Cmd cmd, const CommandArgs& args, const std::string& fragment, const std::vector<std::string>& kept) {
  std::vector<std::string> before;
  for (const auto& k : kept) before.push_back(slurp(k));
  try {
    cmd(args);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
  for (size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(slurp(kept[i]), before[i]) << kept[i] << " changed";
}

const CommandArgs small = {"--solver", "cholmod", "--set", "resolution=4"};
CommandArgs run_args(const std::string& scene, const CommandArgs& more) {
  CommandArgs a = {"--scene", scene};
  a.insert(a.end(), small.begin(), small.end());
  a.insert(a.end(), more.begin(), more.end());
  return a;
}
}  // namespace

TEST(InputsNeverOutputs, RunOutIsNeverTheSceneMeshProfileOrState) {
  TempDir d;
  const std::string scene = d / "scene.toml", profile = d / "profile.toml";
  write(scene, "scene = \"cloth_hang\"\n");
  write(profile, "rtol = 1e-6\n");
  // Another spelling of the same file, and a symbolic link to it: identity, not text.
  fs::create_directories(d.path / "x");
  expect_refused(cmd_run, run_args(scene, {"--out", (d.path / "." / "x" / ".." / "scene.toml").string()}), "an input of this command", {scene});
  fs::create_symlink(scene, d / "link.h5");
  expect_refused(cmd_run, run_args(scene, {"--out", d / "link.h5"}), "an input of this command", {scene});
  expect_refused(cmd_run, run_args("cloth_hang", {"--profile", profile, "--out", profile}), "an input of this command", {profile});
  const std::string mesh = d / "cube.mesh";
  fs::copy_file(std::string(XB_SOURCE_DIR) + "/tests/data/good/cube.mesh", mesh);
  expect_refused(cmd_run, {"--scene", "squash", "--solver", "cholmod", "--set", "mesh=" + mesh, "--out", mesh}, "an input of this command", {mesh});
  // A state file: saved by one run, then named as the next one's --out and --save-state.
  const std::string state = d / "state.h5", out = d / "out.h5";
  ASSERT_EQ(cmd_run(run_args("cloth_hang", {"--save-state", state, "--frame-of-state", "0", "--out", out})), 0);
  expect_refused(cmd_run, run_args("cloth_hang", {"--load-state", state, "--out", state}), "an input of this command", {state});
  expect_refused(cmd_run, run_args(scene, {"--save-state", scene, "--frame-of-state", "0", "--out", d / "o2.h5"}),
                 "an input of this command", {scene});
  expect_refused(cmd_run, run_args(scene, {"--save-state", out, "--frame-of-state", "0", "--out", out}), "--save-state", {out});
}

TEST(InputsNeverOutputs, CaptureNeverReplacesAResultsFileOrItsScene) {
  TempDir d;
  const std::string results = d / "r.h5";
  ASSERT_EQ(cmd_run(run_args("cloth_hang", {"--out", results})), 0);
  const CommandArgs cap = {"--scene", "cloth_hang", "--set", "resolution=4", "--frame", "0", "--iteration", "0", "--out"};
  CommandArgs a = cap;
  a.push_back(d / "r");  // PREFIX.h5 = the results file
  expect_refused(cmd_capture, a, "a results file", {results});
  EXPECT_FALSE(fs::exists(d / "r_A.mtx"));  // refused before anything was written
  // A scene file that one of the prefix's files would replace (PREFIX_A.mtx).
  const std::string scene = d / "s_A.mtx";
  write(scene, "scene = \"cloth_hang\"\nresolution = 4\n");
  expect_refused(cmd_capture, {"--scene", scene, "--frame", "0", "--iteration", "0", "--out", d / "s"}, "an input of this command", {scene});
}

TEST(InputsNeverOutputs, SolveOutIsNeverTheSystem) {
  TempDir d;
  const std::string prefix = d / "sys";
  ASSERT_EQ(cmd_capture({"--scene", "cloth_hang", "--set", "resolution=4", "--frame", "0", "--iteration", "0", "--out", prefix}), 0);
  fs::create_hard_link(prefix + ".h5", d / "hard.h5");
  expect_refused(cmd_solve, {"--system", prefix + ".h5", "--solver", "cholmod", "--out", d / "hard.h5"}, "an input of this command",
                 {prefix + ".h5"});
}

TEST(InputsNeverOutputs, SweepOutIsNeverTheSpecNorAnotherFile) {
  TempDir d;
  const std::string spec = d / "s.toml", other = d / "notes.h5";
  write(spec, "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nresolution = 4\n");
  write(other, "my notes\n");
  expect_refused(cmd_sweep, {spec, "--out", spec}, "an input of this command", {spec});
  expect_refused(cmd_sweep, {spec, "--out", other}, "not an xpbd-bench results file", {other});
}

TEST(InputsNeverOutputs, RunAndSolveReplaceOnlyResultsFiles) {
  TempDir d;
  const std::string notes = d / "notes.txt";
  write(notes, "keep me\n");
  expect_refused(cmd_run, run_args("cloth_hang", {"--out", notes}), "exists and is not an xpbd-bench results file", {notes});
  // A results file is replaced, as documented.
  const std::string results = d / "r.h5";
  ASSERT_EQ(cmd_run(run_args("cloth_hang", {"--out", results})), 0);
  ASSERT_EQ(cmd_run(run_args("cloth_hang", {"--out", results})), 0);
  EXPECT_EQ(count_runs(results), 1);
}

TEST(InputsNeverOutputs, OutputFoldersAreCheckedBeforeTheFirstRun) {
  TempDir d;
  const std::string file = d / "file", out = d / "out.h5";
  write(file, "x");
  expect_refused(cmd_run, run_args("cloth_hang", {"--write-meshes", file, "--out", out}), "is not a directory", {file});
  expect_refused(cmd_run, run_args("cloth_hang", {"--write-meshes", file + "/sub", "--out", out}), "cannot create directory", {file});
  EXPECT_FALSE(fs::exists(out));  // no run happened
  expect_refused(cmd_run, run_args("cloth_hang", {"--out", d / "dir/"}), "is a directory", {});
  expect_refused(cmd_run, run_args("cloth_hang", {"--out", d.path.string()}), "is a directory", {});
  expect_refused(cmd_run, run_args("cloth_hang", {"--out", file + "/r.h5"}), "is not a directory", {file});
  // A missing folder is made, then the runs go there.
  ASSERT_EQ(cmd_run(run_args("cloth_hang", {"--write-meshes", d / "meshes", "--out", (d.path / "new" / "r.h5").string()})), 0);
  EXPECT_TRUE(fs::is_regular_file(d.path / "new" / "r.h5"));
  EXPECT_FALSE(fs::is_empty(d / "meshes"));
}

TEST(InputsNeverOutputs, TemporaryFilesAreRemovedOnEveryFailure) {
  TempDir d;
  const std::string target = d / "t.txt";
  try {
    TmpFile tmp(target);
    write(tmp.path(), "partial");
    throw Error("the writer failed");
  } catch (const Error&) {
  }
  auto no_tmp = [&] {
    for (const auto& e : fs::recursive_directory_iterator(d.path)) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
  };
  no_tmp();
  EXPECT_FALSE(fs::exists(target));
  // A failed rename: the target is a non-empty folder.
  const std::string folder = d / "taken";
  fs::create_directories(fs::path(folder) / "inside");
  RunRecord r;
  r.name = "x";
  r.attrs["status"] = std::string("ok");
  EXPECT_THROW(append_runs(folder, {r}, true), Error);
  no_tmp();
  for (const auto& e : fs::directory_iterator(runs_folder(folder))) EXPECT_EQ(e.path().filename(), "lock") << "run file left";
  EXPECT_TRUE(fs::is_directory(fs::path(folder) / "inside"));
}

// A results file whose second run is an array where a scalar attribute belongs (a crash once):
// read run by run, the bad one named and left out; strict reading throws naming it.
TEST(HostileResults, UnreadableRunsAreNamedAndSkipped) {
  const std::string file = std::string(XB_SOURCE_DIR) + "/tests/data/hostile/attr_int_array.h5";
  std::vector<std::string> skipped;
  const auto runs = read_runs(file, false, &skipped);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].name, "0001_cloth_hang_cholmod");
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("run 0002_cloth_hang_bad attribute 'status': is an array of 3 values"), std::string::npos) << skipped[0];
  EXPECT_NE(skipped[0].find(file), std::string::npos) << skipped[0];
  EXPECT_THROW(read_runs(file, true), Error);
}
