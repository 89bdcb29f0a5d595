// No silent no-ops (harness/key_check.hpp): the θ_s sweep of the squash that gave five identical
// rows is refused naming the key that applies, and runs once the form is dual; keys set by the
// command are checked against its runs, keys of a scene file or profile against their scene;
// every stock scene with every profile and method passes; every key declares where it applies.
#include "core/error.hpp"
#include "harness/cli/profile.hpp"
#include "harness/cli/run_setup.hpp"
#include "harness/cli/sweep.hpp"
#include "harness/key_check.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

namespace fs = std::filesystem;
using namespace xb;

namespace {
// What check_run_keys says for these runs ("" = accepted).
std::string refusal(const Params& p, const std::vector<std::string>& methods, const std::string& forms = "",
                    bool form_flag = false) {
  try {
    check_run_keys(p, method_runs(methods, forms), form_flag, false, "run");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("xb_key_check_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return (dir / name).string();
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }
}  // namespace

// The example: squash resolves form = auto to primal, where mgpbd reads
// amg.nodal_strength_threshold; amg.strength_threshold is refused, naming it, at any value.
TEST(KeyCheck, StrengthThresholdUnderThePrimalFormNamesTheNodalKey) {
  for (const char* v : {"0.1", "0.25"}) {  // 0.25 is the default: set where nothing reads it, refused too
    const Params p = resolve_params("squash", {std::string("amg.strength_threshold=") + v});
    const std::string why = refusal(p, {"mgpbd"});
    EXPECT_TRUE(has(why, "--set: parameter 'amg.strength_threshold' has no effect in this run (mgpbd, primal form)")) << why;
    EXPECT_TRUE(has(why, "here the key that applies is 'amg.nodal_strength_threshold'")) << why;
  }
  EXPECT_EQ(refusal(resolve_params("squash", {"form=dual", "amg.strength_threshold=0.1"}), {"mgpbd"}), "");
  EXPECT_EQ(refusal(resolve_params("squash", {"amg.nodal_strength_threshold=0.1"}), {"mgpbd"}), "");
  // One run of the command that reads it is enough: the dual run of --form dual,primal, or hypre.
  const Params p = resolve_params("squash", {"amg.strength_threshold=0.1"});
  EXPECT_EQ(refusal(p, {"mgpbd"}, "dual,primal"), "");
  EXPECT_EQ(refusal(p, {"mgpbd", "hypre"}), "");
  EXPECT_TRUE(has(refusal(p, {"cholmod", "xpbd-gs"}), "has no effect in any run here (cholmod, primal form; xpbd-gs"));
}

TEST(KeyCheck, SweepRefusesAGridAxisThatChangesNothing) {
  const std::string grid = "scene = \"squash\"\nsolvers = [\"mgpbd\"]\n[set]\nmax_iterations = 2\n%s[grid]\n"
                           "\"amg.strength_threshold\" = [0.0, 0.05, 0.1, 0.25, 0.5]\n";
  const std::string primal = write("theta_primal.toml", std::string(grid).replace(grid.find("%s"), 2, ""));
  try {
    expand_sweep(parse_sweep_spec(primal));
    ADD_FAILURE() << "the primal sweep of amg.strength_threshold was accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(has(e.what(), "[grid] axis 'amg.strength_threshold': parameter 'amg.strength_threshold' has no effect")) << e.what();
    EXPECT_TRUE(has(e.what(), "'amg.nodal_strength_threshold'")) << e.what();
  }
  const std::string dual = write("theta_dual.toml", std::string(grid).replace(grid.find("%s"), 2, "form = \"dual\"\n"));
  const auto jobs = expand_sweep(parse_sweep_spec(dual));
  ASSERT_EQ(jobs.size(), 5u);
  std::set<double> thetas;
  for (const auto& j : jobs) thetas.insert(j.params.amg.strength_threshold);
  EXPECT_EQ(thetas.size(), 5u);
  // A [set] key no run reads is refused the same way, naming the spec.
  const std::string set = write("set_noop.toml", "scene = \"squash\"\nsolvers = [\"cholmod\"]\n[set]\n\"amg.smoother\" = \"jacobi\"\n");
  try {
    expand_sweep(parse_sweep_spec(set));
    ADD_FAILURE() << "amg.smoother for cholmod was accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(has(e.what(), "set_noop.toml: [set] 'amg.smoother': parameter 'amg.smoother' has no effect")) << e.what();
  }
}

// A scene file or profile may set keys for other methods (the race runs each scene with every
// method), not keys no run of its scene reads.
TEST(KeyCheck, FileKeysMustBeReadBySomeRunOfTheirScene) {
  const std::string twist = write("squash_twist.toml", "scene = \"squash\"\nresolution = 3\ntwist = 0.5\n");
  std::string why = refusal(resolve_params(twist, {}), {"cholmod"});
  EXPECT_TRUE(has(why, "squash_twist.toml:3: parameter 'twist' has no effect in any run of scene 'squash'")) << why;
  const std::string compliance = write("squash_compliance.toml", "scene = \"squash\"\ncompliance = 1e-6\n");
  why = refusal(resolve_params(compliance, {}), {"cholmod"});
  EXPECT_TRUE(has(why, "squash_compliance.toml:2") && has(why, "here the key that applies is 'stiffness'")) << why;
  // The file's amg.strength_threshold is for the runs that read it: no refusal under cholmod.
  const std::string amg = write("squash_amg.toml", "scene = \"squash\"\n[amg]\nstrength_threshold = 0.1\n");
  EXPECT_EQ(refusal(resolve_params(amg, {}), {"cholmod"}), "");
  // The same key set by the command for a run that cannot read it is refused.
  why = refusal(resolve_params("cloth_hang", {"variant=mu1e12"}), {"cholmod"});
  EXPECT_TRUE(has(why, "parameter 'variant'") && has(why, "'compliance'")) << why;
}

TEST(KeyCheck, EveryStockSceneWithEveryProfileAndMethodPasses) {
  for (const auto& scene : scene_names())
    for (const std::string profile : {"", "newton", "authors"}) {
      const Params p = resolve_params(scene, {}, profile);
      for (const auto& m : methods()) {
        if (!m.available) continue;
        EXPECT_EQ(refusal(p, {m.name}), "") << scene << " --profile " << profile << " " << m.name;
      }
    }
}

TEST(KeyCheck, FormFlagAndFormKeyTogetherAreRefused) {
  const Params p = resolve_params("cloth_hang", {"form=dual"});
  EXPECT_TRUE(has(refusal(p, {"cholmod"}, "primal", true), "--form and --set form=dual both choose the form")) << refusal(p, {"cholmod"}, "primal", true);
  EXPECT_EQ(refusal(resolve_params("cloth_hang", {}), {"cholmod"}, "primal", true), "");
}

TEST(KeyCheck, SolveRunsReadOnlyTheLinearKeys) {
  auto solve = [](Params p, const std::string& method, const std::string& form) {
    try {
      check_keys({CommandRun{std::move(p), method, false, true, form}});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  Params p;
  set_param(p, "dt", "0.01", "--set");
  EXPECT_TRUE(has(solve(p, "mgpbd", "dual"), "'dt' has no effect in this run (mgpbd, dual form, one solve of a captured system)"));
  Params q;
  set_param(q, "amg.strength_threshold", "0.1", "--set");
  EXPECT_EQ(solve(q, "mgpbd", "dual"), "");
  EXPECT_TRUE(has(solve(q, "mgpbd", "primal"), "'amg.nodal_strength_threshold'"));
  Params r;
  set_param(r, "linear.tol", "1e-6", "solve --tol");
  set_param(r, "threads", "2", "--set");  // recorded only: accepted anywhere
  EXPECT_EQ(solve(r, "cg", "primal"), "");
}

// Every key declares where it applies; every condition names a key and, for a key with choices,
// values it can take; every key named instead exists.
TEST(KeyCheck, EveryKeyDeclaresAValidScope) {
  for (const auto& f : param_fields()) {
    EXPECT_NE(f.scope.kind, KeyScope::Kind::undeclared) << f.key << ": add .applies(...) or .record_only(...) to its row";
    std::vector<Scope> all = f.scope.any;
    for (const auto& [s, other] : f.scope.instead) {
      all.push_back(s);
      EXPECT_NE(find_param(other), nullptr) << f.key << " names an unknown key instead: " << other;
    }
    for (const auto& s : all) {
      for (const auto& m : s.methods)
        EXPECT_TRUE(m == "local" || m == "global" || m == "python" || find_method(m)) << f.key << ": unknown method " << m;
      for (const auto& form : s.forms) EXPECT_TRUE(form == "dual" || form == "primal") << f.key << ": form " << form;
      for (const auto& text : s.when) {
        const Condition c = parse_condition(text);
        const ParamField* g = find_param(c.key);
        ASSERT_NE(g, nullptr) << f.key << ": condition on unknown key " << c.key;
        if (!g->choices.empty() && (c.op == "=" || c.op == "!="))
          for (const auto& v : c.values)
            EXPECT_NE(std::find(g->choices.begin(), g->choices.end(), v), g->choices.end()) << f.key << ": " << text;
      }
    }
  }
}
