#include "key_effects_support.hpp"

#include "core/error.hpp"
#include "harness/cli/profile.hpp"
#include "harness/key_check.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"
#include "solvers/kernels.hpp"
#include "solvers/linear_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace xb::test {

namespace {

// Plain CG to the tolerance the harness sets, nothing read from the settings: what a Python
// solver of the protocol sees (python/src/api.cpp hands it linear.tol, then the forcing rule's).
class TolOnlyCg final : public LinearSolver {
 public:
  explicit TolOnlyCg(double tol) : LinearSolver(tol) {}
  std::string name() const override { return "py:test"; }
  void setup(const SparseMatrix& A, SetupKind, const SetupContext&) override { A_ = &A; }
  LinearStats solve(const Vector& b, Vector& x) override {
    LinearStats st;
    x = Vector::Zero(b.size());
    Vector r = b, p = b, Ap;
    const double bnorm = norm2(b);
    double rr = dot(r, r);
    while (std::sqrt(rr) > tolerance() * bnorm && st.iterations < 10000) {
      spmv(*A_, p, Ap);
      const double a = rr / dot(p, Ap);
      x += a * p;
      r -= a * Ap;
      const double next = dot(r, r);
      p = r + (next / rr) * p;
      rr = next;
      ++st.iterations;
    }
    st.final_relative_residual = bnorm > 0 ? std::sqrt(rr) / bnorm : 0;
    return st;
  }

 private:
  const SparseMatrix* A_ = nullptr;
};

const std::vector<std::string> tiny_scene_keys = {"resolution", "frames", "max_iterations"};

// A stock scene at a size that runs in milliseconds, two frames of a few outer iterations.
Params tiny_scene(const std::string& scene) {
  Params p;
  load_scene_file(resolve_scene(scene), p);
  const int res = scene == "cloth_hang" || scene == "squash" || scene == "ball_drop" ? 4
                  : scene == "mass_chain" || scene == "heavy_rope"                    ? 8
                  : scene == "pendulum"                                               ? 6
                                                                                      : 2;
  set_param(p, "resolution", std::to_string(res), "tiny");
  if (scene == "twist_bar" || scene == "cantilever") set_param(p, "aspect", "2", "tiny");
  if (scene == "ball_drop") set_param(p, "dt", "0.05", "tiny");  // in contact from the first frame
  set_param(p, "frames", "2", "tiny");
  set_param(p, "max_iterations", "4", "tiny");
  set_param(p, "threads", "1", "tiny");  // OpenMP on runs this small only waits for its threads
  p.set_by_command.clear();
  return p;
}

// Runs of every method on the small twisted bar: each global method in both forms under the
// fixed step and the line search, and under Newton's profile (primal); coarse levels made small
// enough that the bar's AMG hierarchies have several.
std::vector<Context> method_contexts() {
  Params bar = tiny_scene("twist_bar");
  set_param(bar, "max_iterations", "8", "tiny");
  set_param(bar, "rtol", "0.2", "tiny");  // most methods stop on it within the 8 iterations
  set_param(bar, "amg.max_coarse", "8", "tiny");
  set_param(bar, "muelu.coarse_size", "8", "tiny");
  bar.set_by_command.clear();
  std::vector<Context> out;
  std::vector<std::string> globals;
  for (const auto& m : methods()) {
    if (!m.available) continue;
    if (m.local) {
      out.push_back({m.name, bar, m.name});
      // Block descent's keys on contact and on compliant distances: the ball and the cloth.
      if (m.name == "vbd" || m.name == "avbd")
        for (const char* scene : {"ball_drop", "cloth_hang"}) {
          Params q = tiny_scene(scene);
          q.set_by_command.clear();
          out.push_back({m.name + " " + scene, q, m.name});
        }
      continue;
    }
    globals.push_back(m.name);
  }
  globals.push_back("py:test");
  for (const auto& m : globals) {
    for (const char* form : {"dual", "primal"})
      for (const char* step : {"fixed", "line_search"}) {
        Context c{m + " " + form + " " + step, bar, m};
        c.params.form = form;
        c.params.step = step;
        out.push_back(std::move(c));
      }
    Context n{m + " newton", bar, m};
    apply_profile("newton", n.params);
    n.params.set_in_file.clear();
    out.push_back(std::move(n));
  }
  return out;
}

bool condition_holds(const Params& p, const std::string& condition) {
  return in_scope(on("").where(condition), run_site(CommandRun{p, ""}));
}

// Makes `condition` true in p by setting its key (not the key under test, and not the step or
// the scene: those pick the runs). Returns false where it cannot.
bool satisfy(Params& p, const std::string& condition, const std::string& tested, std::string& name) {
  if (condition_holds(p, condition)) return true;
  const Condition c = parse_condition(condition);
  if (c.key == tested || c.key == "step" || c.key == "scene" || c.key == "form") return false;
  const ParamField& f = *find_param(c.key);
  std::string v;
  if (c.op == "=") {
    v = c.values[0];
  } else if (c.op == "!=") {
    for (const auto& choice : f.choices)
      if (std::find(c.values.begin(), c.values.end(), choice) == c.values.end()) v = choice;
  } else {
    v = std::to_string(std::stod(c.values[0]) + (c.op == ">" ? 1 : -1));
  }
  try {
    set_param(p, c.key, v, "context");
  } catch (const Error&) {
    return false;
  }
  name += " " + c.key + "=" + v;
  return condition_holds(p, condition);
}

// The contexts again with one clause of the key's scope made true, where a context can be.
void add_clause_contexts(const ParamField& f, const Scope& clause, const std::vector<Context>& bases,
                         std::vector<Context>& out, std::set<std::string>& seen) {
  for (const Context& b : bases) {
    Context c = b;
    c.reference = b.reference || clause.reference;
    if (clause.reference) c.name += " --reference";
    bool ok = true;
    for (const auto& cond : clause.when) ok = ok && satisfy(c.params, cond, f.key, c.name);
    c.params.set_by_command.clear();
    if (!ok || !in_scope(clause, run_site(CommandRun{c.params, c.method, c.reference}))) continue;
    if (seen.insert(c.name).second) out.push_back(std::move(c));
  }
}

}  // namespace

void register_test_solver() {
  if (find_method("py:test")) return;
  register_method({"py:test", false, true, "", "CG that reads only its tolerance"},
                  [](const SolverSettings& s) { return std::make_unique<TolOnlyCg>(s.linear.tol); });
}

// Keys that act only near convergence: their runs go there.
// The linear keys of cholmod with a lagged factor: on the small bar in the primal form the old
// factor's CG gives up at the default lagged_max_iterations on every solve, which then refactorises
// and ends exact; a cap of 1000 lets it run.
const std::pair<std::string, std::string> lagged_runs{"cholmod.lagged_max_iterations", "1000"};
const std::map<std::string, std::vector<std::pair<std::string, std::string>>> extra_settings = {
    {"xpbd.line_search", {{"rtol", "0"}, {"atol", "0"}, {"max_iterations", "30"}}},
    {"linear.tol", {lagged_runs}},
    {"linear.forcing", {lagged_runs}},
    {"linear.forcing_max", {lagged_runs}},
    {"linear.forcing_gamma", {lagged_runs}},
    {"linear.forcing_alpha", {lagged_runs, {"linear.forcing_max", "0.9"}}},  // below the cap the sequence is alpha's
    {"linear.stop_norm", {lagged_runs, {"mass_ratio", "100"}}},  // graded masses: a Jacobi scaling that is not uniform
};

std::vector<Context> contexts_for(const ParamField& f) {
  const bool scene_key = find_setting(scene_settings(), f.key) != nullptr;
  std::vector<Context> bases;
  if (scene_key) {
    for (const auto& s : scene_names()) bases.push_back({s + " xpbd-gs", tiny_scene(s), "xpbd-gs"});
  } else {
    bases = method_contexts();
  }
  if (auto it = extra_settings.find(f.key); it != extra_settings.end())
    for (auto& b : bases)
      for (const auto& [k, v] : it->second) {
        set_param(b.params, k, v, "extra");
        b.params.set_by_command.clear();  // the base of the runs, not what a command sets
      }
  std::vector<Context> out = bases;
  std::set<std::string> seen;
  for (const auto& c : out) seen.insert(c.name);
  for (const auto& clause : f.scope.any) add_clause_contexts(f, clause, bases, out, seen);
  for (const auto& [clause, other] : f.scope.instead) add_clause_contexts(f, clause, bases, out, seen);
  return out;
}

std::vector<std::string> probe_values(const ParamField& f, const Params& p) {
  const std::string now = param_to_string(p, f);
  std::vector<std::string> out;
  auto add = [&](const std::string& v) {
    if (v != now && std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  };
  if (f.type == SettingType::String) {
    for (const auto& c : f.choices) add(c);
    if (f.key == "mesh") add("bar"), add("ball");
    if (f.key == "pins.indices") add("0"), add("5"), add("20");
    if (f.key == "pins.box") add("-1e3, -1e3, -1e3, 1e3, 1e3, 1e3");  // every particle
    if (f.key == "ground") add("none"), add("1e3");                    // a plane above every particle
    return out;
  }
  const double v = std::stod(now);
  // Integers are sizes and counts: halved and doubled (ten times a mesh's resolution is a big run).
  std::vector<double> xs = {2 * v, v / 2, v + 1, v - 1};
  if (f.type == SettingType::Double) xs.insert(xs.end(), {10 * v, v / 10, 1e3 * (std::abs(v) + 1)});  // last: far off
  if (v == 0) xs.insert(xs.end(), {0.5, 0.1});
  for (double bound : {f.min, f.max})
    if (std::abs(bound) <= 100) xs.insert(xs.end(), {bound, (v + bound) / 2});
  for (double x : xs) {
    if (x < f.min || x > f.max || x == v) continue;
    if (f.type == SettingType::Int && x != std::floor(x)) continue;
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", x);
    add(b);
  }
  return out;
}

Outcome run_outcome(const Params& p, const std::string& method, bool reference) {
  Outcome o;
  try {
    const Problem prob = build_problem(p);
    RunOptions opt;
    opt.reference = reference;
    const RunResult r = run_simulation(prob, p, method, opt);
    o.error = r.status == "error";
    o.message = r.message;
    o.status = r.status;
    o.reference_method = r.reference_method;
    o.outer_iterations = r.outer_iterations;
    o.x.assign(r.final_positions.data(), r.final_positions.data() + r.final_positions.size());
    const auto& L = r.log;
    for (const auto* v : {&L.dual_residual, &L.position_error, &L.reference_relative_dual_residual, &L.energy})
      o.logged.insert(o.logged.end(), v->begin(), v->end());
    o.counts = L.linear_iterations;
    o.counts.insert(o.counts.end(), L.reference_iterations.begin(), L.reference_iterations.end());
    for (const auto& [k, v] : r.stats)
      if (k.find("time") == std::string::npos && k != "peak_memory") o.stats[k] = v;  // the process's, not the run's
  } catch (const Error& e) {
    o.error = true;
    o.message = e.what();
  }
  return o;
}

}  // namespace xb::test
