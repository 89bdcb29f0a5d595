// sweep with a profile: the spec's `profile` key and `sweep --profile` apply the profile between
// the scene and [set]/[grid], change the sweep's base, and every run records `profile`.
#include "harness/cli/sweep.hpp"
#include "harness/io/run_record.hpp"
#include "core/error.hpp"

#include "../../test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

using namespace xb;

namespace {
std::string write(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}
const char* kSpec = "scene = \"squash\"\nsolvers = [\"cholmod\"]\nframes = 1\n[set]\nresolution = 4\nmax_iterations = 2\n"
                    "step = \"fixed\"\n[grid]\nrtol = [1e-2, 1e-3]\n";
}  // namespace

TEST(SweepProfile, SpecKeyAndOptionApplyTheProfile) {
  const test::TempDir dir;
  const std::string plain = write(dir / "plain.toml", kSpec);
  const std::string with = write(dir / "with.toml", std::string("profile = \"authors\"\n") + kSpec);
  for (const SweepSpec& s : {parse_sweep_spec(with), parse_sweep_spec(plain, "default", "authors")}) {
    EXPECT_EQ(s.profile, "authors");
    for (const auto& j : expand_sweep(s)) {
      EXPECT_EQ(j.params.profile, "authors");
      EXPECT_EQ(j.params.residual_metric, "authors");  // from the profile
      EXPECT_EQ(j.params.mesh_height, 0.2);            // its [scenes.squash] table
      EXPECT_EQ(j.params.step, "fixed");               // [set] after the profile
    }
  }
  const SweepSpec none = parse_sweep_spec(plain);
  EXPECT_EQ(expand_sweep(none)[0].params.profile, "");
  EXPECT_EQ(expand_sweep(none)[0].params.residual_metric, "true");
  EXPECT_NE(sweep_base_hash(none), sweep_base_hash(parse_sweep_spec(with)));
  EXPECT_EQ(sweep_base_hash(parse_sweep_spec(with)), sweep_base_hash(parse_sweep_spec(plain, "default", "authors")));
  const std::string bad = write(dir / "bad.toml", std::string("profile = \"no_such_profile\"\n") + kSpec);
  try {
    parse_sweep_spec(bad);
    FAIL() << "an unknown profile was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.toml:1"), std::string::npos) << e.what();
  }
}

TEST(SweepProfile, RunsRecordTheProfile) {
  const test::TempDir dir;
  const std::string bench = std::string(XB_BINARY_DIR) + "/xpbd-bench";
  const std::string spec = write(dir / "s.toml", kSpec), out = dir / "s.h5";
  ASSERT_EQ(std::system((bench + " sweep " + spec + " --profile authors --out " + out + " >/dev/null 2>&1").c_str()), 0);
  const auto runs = read_runs(out, false);
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& r : runs) EXPECT_EQ(test::attr_string(r, "profile"), "authors");
  EXPECT_NE(std::system((bench + " sweep " + spec + " --profile nope --out " + (dir / "n.h5") + " >/dev/null 2>&1").c_str()), 0);
}
