// The typed settings table (core/settings.hpp) and its composition into the flat key space
// (harness/params.hpp): the words of each parse error, parts routed to their own struct, and every
// solver key reaching SolverSettings unchanged.
#include "core/error.hpp"
#include "core/settings.hpp"
#include "harness/params.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace xb;

namespace {
struct Part {
  int n = 1;
  double x = 0.5;
  std::string s = "a";
};
struct Whole {
  Part first, second;
};
const SettingTable<Part>& part_table() {
  static const SettingTable<Part> t = {
      setting("n", "an int", &Part::n, 0, 10),
      setting("x", "a double", &Part::x, 1e-300, 1),
      setting("s", "a choice", &Part::s, {"a", "b"}),
  };
  return t;
}
std::string error_of(Part& p, const std::string& key, const std::string& value) {
  try {
    set_setting(part_table(), p, key, value, "here");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Settings, ParseErrorsSayWhatIsWrong) {
  Part p;
  EXPECT_NE(error_of(p, "n", "abc").find("not a number"), std::string::npos);
  EXPECT_NE(error_of(p, "n", "").find("not a number"), std::string::npos);
  EXPECT_NE(error_of(p, "x", "nan").find("not finite"), std::string::npos);
  EXPECT_NE(error_of(p, "x", "-inf").find("not finite"), std::string::npos);
  // Too large or too small for a double, or outside the key's bounds: out of range, not "not a number".
  EXPECT_NE(error_of(p, "n", "1e12").find("out of range"), std::string::npos);
  EXPECT_NE(error_of(p, "x", "1e999").find("out of range"), std::string::npos);
  EXPECT_NE(error_of(p, "x", "1e-320").find("out of range"), std::string::npos);
  EXPECT_NE(error_of(p, "n", "2.5").find("must be an integer"), std::string::npos);
  EXPECT_NE(error_of(p, "s", "c").find("must be one of a, b"), std::string::npos);
  const std::string unknown = error_of(p, "m", "1");
  EXPECT_NE(unknown.find("unknown parameter 'm' (valid: n, x, s)"), std::string::npos);
  EXPECT_EQ(unknown.rfind("here: ", 0), 0u);
  // Nothing was set by a refused value.
  EXPECT_EQ(p.n, 1);
  EXPECT_EQ(p.x, 0.5);
  EXPECT_EQ(error_of(p, "n", "7"), "");
  EXPECT_EQ(p.n, 7);
}

// A struct filled in code is checked against its table with the parse errors' words.
TEST(Settings, CheckSettingsRefusesWhatTheTableRefuses) {
  Part p;
  EXPECT_NO_THROW(check_settings(part_table(), p, "here"));
  p.s = "c";
  try {
    check_settings(part_table(), p, "here");
    ADD_FAILURE() << "s = c accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("must be one of a, b"), std::string::npos) << e.what();
  }
  p.s = "b";
  p.n = 11;
  EXPECT_THROW(check_settings(part_table(), p, "here"), Error);
  p.n = 10;
  p.x = 0;
  EXPECT_THROW(check_settings(part_table(), p, "here"), Error);
}

TEST(Settings, PartsRouteToTheirOwnStruct) {
  SettingTable<Whole> t;
  append_part(t, part_table(), [](Whole& w) -> Part& { return w.second; });
  Whole w;
  set_setting(t, w, "n", "3", "test");
  EXPECT_EQ(w.second.n, 3);
  EXPECT_EQ(w.first.n, 1);
  EXPECT_EQ(setting_text(*find_setting(t, "n"), w), "3");
  EXPECT_EQ(std::get<std::string>(setting_value(*find_setting(t, "s"), w)), "a");
}

TEST(Settings, ParamsComposeEveryComponentOnce) {
  std::set<std::string> keys;
  for (const auto& f : param_fields()) EXPECT_TRUE(keys.insert(f.key).second) << "duplicate key " << f.key;
  // Each component's keys are in the flat space under their own names.
  for (const auto& f : solver_settings()) EXPECT_TRUE(keys.count(f.key)) << f.key;
  for (const auto& f : scene_settings()) EXPECT_TRUE(keys.count(f.key)) << f.key;
  for (const auto& f : stepper_settings()) EXPECT_TRUE(keys.count(f.key)) << f.key;
  EXPECT_EQ(keys.size(), solver_settings().size() + scene_settings().size() + stepper_settings().size());
  // A flat key lands in the component that owns it.
  Params p;
  set_param(p, "amg.strength_threshold", "0.125", "test");
  set_param(p, "linear.tol", "1e-5", "test");
  set_param(p, "muelu.smoother_sweeps", "3", "test");
  set_param(p, "xpbd.position_relaxation", "0.25", "test");
  set_param(p, "variant", "mu1e12", "test");
  const SolverSettings& s = p;
  EXPECT_EQ(s.amg.strength_threshold, 0.125);
  EXPECT_EQ(s.linear.tol, 1e-5);
  EXPECT_EQ(s.muelu.smoother_sweeps, 3);
  EXPECT_EQ(s.xpbd.position_relaxation, 0.25);
  EXPECT_EQ(p.stiffness, 1e12);  // the variant's implied key
}

TEST(Settings, SolverSettingsRoundTripAsText) {
  // The MPI workers rebuild SolverSettings from rank 0's key=value lines.
  SolverSettings a;
  a.amg.smoother.kind = "block_gs";
  a.hypre.max_levels = 7;
  a.linear.tol = 3.25e-7;
  a.seed = 11;
  SolverSettings b;
  for (const auto& f : solver_settings()) set_setting(solver_settings(), b, f.key, setting_text(f, a), "roundtrip");
  for (const auto& f : solver_settings()) EXPECT_EQ(setting_text(f, a), setting_text(f, b)) << f.key;
  EXPECT_EQ(b.amg.smoother.kind, "block_gs");
  EXPECT_EQ(b.hypre.max_levels, 7);
}
