// Every key in every kind of run (harness/key_check.hpp, core/key_scope.hpp). For each key of the
// flat key space and each kind of run — every method, each global one in both forms under the
// fixed step, the line search and Newton on E, every stock scene for the scene's keys, and the
// runs its own scope's conditions pick (amg.near_kernel = gs, cholmod.refactor = lagged,
// --reference, ...) — the key is set to a few values besides the base one and the run is made
// with the key check bypassed. Where the key's declared scope says it has an effect, one of the
// values must change the run; where it says it has none, no value may change it (a value that
// makes the run fail is a refusal, not a change). So a scope that hides an effect (a refused key
// that did something) fails, and so does one that claims an effect that is not there (a silent
// no-op); a key with no declaration fails too. One ctest per key.
#include "key_effects_support.hpp"

#include "core/error.hpp"
#include "harness/key_check.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <set>
#include <tuple>
#include <sstream>

using namespace xb;
using namespace xb::test;

namespace {

class MpiEnv : public ::testing::Environment {
 public:
  void SetUp() override {
    int done = 0;
    MPI_Initialized(&done);
    if (!done) owned_ = MPI_Init(nullptr, nullptr) == MPI_SUCCESS;
    register_test_solver();
  }
  void TearDown() override {
    int done = 0;
    MPI_Finalized(&done);
    if (owned_ && !done) MPI_Finalize();
  }

 private:
  bool owned_ = false;
};
const auto* const mpi_env = ::testing::AddGlobalTestEnvironment(new MpiEnv);

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// Where a key is read but its effect cannot show on runs this small, and why; every entry names
// runs of the same key elsewhere in its scope where it does show.
const std::vector<std::tuple<std::string, std::string, std::string>> invisible = {
    {"residual_metric", "xpbd-jacobi", "the relaxed Jacobi sweep never reaches rtol on the small bar: no stop test passes"},
    {"residual_metric", "xpbd-authors", "its sweep, relaxed by 0.1, never reaches rtol on the small bar: no stop test passes"},
    {"linear.forcing_alpha", "mgpbd", "its first PCG iterations pass both tolerances alpha gives here (the outer ratio is near 1)"},
    {"linear.forcing_alpha", "muelu", "its first CG iterations pass both tolerances alpha gives here"},
    {"linear.forcing_alpha", "lagged", "CG with a factor of a nearby matrix passes both tolerances alpha gives here"},
    {"atol", "vbd", "block descent's |grad E| (N) stays above every atol tried in this run's few sweeps"},
    {"xpbd.line_search", "mgpbd newton",
     "armijo and robust_armijo part only where E cannot resolve a step; mgpbd's inexact steps stop short of that here"},
};
std::string invisible_here(const std::string& key, const std::string& context) {
  for (const auto& [k, c, why] : invisible)
    if (k == key && context.find(c) != std::string::npos) return why;
  return "";
}

class KeyEffect : public ::testing::TestWithParam<std::string> {};

TEST_P(KeyEffect, ChangesTheRunExactlyWhereItsScopeSays) {
  const std::string key = GetParam();
  const ParamField& f = *find_param(key);
  ASSERT_NE(f.scope.kind, KeyScope::Kind::undeclared) << key << " declares no scope (.applies / .record_only in its table row)";
  if (f.scope.kind == KeyScope::Kind::record) GTEST_SKIP() << key << " is recorded only: " << f.scope.record;
  if (key == "scene") GTEST_SKIP() << "the builder: every run has one (another builder refuses the scene's own keys)";
  int with_effect = 0, without = 0;
  bool changed_somewhere = false;
  for (const Context& c : contexts_for(f)) {
    const Outcome base = run_outcome(c.params, c.method, c.reference);
    // Nothing to compare with: a combination the run refuses, or a run that broke down or
    // diverged before the key's part of it (hypre.reuse = hierarchy breaks down at once here).
    if (base.error || (base.status != "ok" && base.status != "max_iterations")) continue;
    bool declared_any = false, changed_any = false, refused_any = false;
    std::vector<std::string> tried;
    // Out of the key's scope two values (the extremes of the list) show that it changes nothing;
    // in it, every value is tried for one that changes the run.
    std::vector<std::string> values = probe_values(f, c.params);
    if (!has_effect(f.scope, run_site(CommandRun{c.params, c.method, c.reference})) && values.size() > 2)
      values = {values.front(), values.back()};
    for (const std::string& v : values) {
      Params q = c.params;
      set_param(q, key, v, "test");
      const bool declared = has_effect(f.scope, run_site(CommandRun{q, c.method, c.reference}));
      const Outcome o = run_outcome(q, c.method, c.reference);
      const bool changed = !o.error && !(o == base);
      tried.push_back(v + (o.error ? " (refused: " + o.message + ")" : changed ? " (changed)" : " (same)"));
      if (declared) {
        declared_any = true;
        changed_any = changed_any || changed;
        refused_any = refused_any || o.error;
      } else {
        EXPECT_FALSE(changed) << key << " = " << v << " changed a run of " << c.name
                              << ", where its scope says it has no effect (" << describe(f.scope) << ")";
      }
    }
    // Where it has an effect, some value changes the run, or is refused (loud, not a silent no-op:
    // under Newton's profile, step and form have no other valid value).
    if (declared_any) {
      ++with_effect;
      changed_somewhere = changed_somewhere || changed_any;
      const std::string why = invisible_here(key, c.name);
      if (!why.empty()) RecordProperty("invisible: " + c.name, why);
      else EXPECT_TRUE(changed_any || refused_any) << key << ": its scope says it has an effect in " << c.name << " ("
                                              << describe(f.scope) << "), but no value changed the run: " << join(tried);
    } else {
      ++without;
    }
    // Where the key has no effect, setting it is refused by name, and the key its message names
    // instead must have an effect there.
    const RunSite site = run_site(CommandRun{c.params, c.method, c.reference});
    if (!has_effect(f.scope, site)) {
      Params q = c.params;
      set_param(q, key, param_to_string(c.params, f), "--set");  // its value here: the default is refused too
      try {
        check_keys({CommandRun{q, c.method, c.reference}});
        ADD_FAILURE() << key << " set in " << c.name << " was not refused";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--set: parameter '" + key + "' has no effect"), std::string::npos) << e.what();
      }
    }
    if (!has_effect(f.scope, site))
      for (const auto& [where, other] : f.scope.instead)
        if (in_scope(where, site))
          EXPECT_TRUE(has_effect(find_param(other)->scope, site))
              << key << " names " << other << " as the key that applies in " << c.name << ", which has no effect there either";
  }
  if (with_effect > 0) EXPECT_TRUE(changed_somewhere) << key << ": no value changed any run it is in scope for";
  if (with_effect + without > 0) EXPECT_GT(with_effect, 0) << key << ": no run tried has it in scope (" << describe(f.scope) << ")";
  RecordProperty("runs_with_effect", with_effect);
  RecordProperty("runs_without", without);
}

std::vector<std::string> all_keys() {
  std::vector<std::string> keys;
  for (const auto& f : param_fields()) keys.push_back(f.key);
  return keys;
}

INSTANTIATE_TEST_SUITE_P(Keys, KeyEffect, ::testing::ValuesIn(all_keys()), [](const auto& info) {
  std::string name = info.param;
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return name;
});

}  // namespace
