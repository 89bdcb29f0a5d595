// xb_perf_metrics: the deterministic half of CI performance tracking.
// For a fixed set of small captured systems and short scenes it records what does not depend
// on the machine's load: iterations to tolerance of every registered linear solver, AMG levels
// and operator/grid complexity (LinearSolver::statistics()), outer iterations per substep of
// every method, and the status of each. It runs single-threaded by default; the counts are the
// same for any thread count (docs/determinism.md). Output: one JSON object
// (scripts/perf.py merges it with the Google Benchmark timings and compares with the baseline).
//
//   xb_perf_metrics [--set key=value]... [--methods a,b,...] [--only linear|sim] [--cases l1,l2,...]
//                   [--threads N] [--out FILE]
// --cases keeps only the named cases of the fixed set (e.g. cloth_hang/r16): for fast tests.
#include "perf_common.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../cli/args.hpp"
#include "../sim/simulation.hpp"

#include <mpi.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace {

using xb::perf::SceneCase;

// The fixed set. Small enough that the whole tool runs in seconds; the gate's baseline
// depends on it, so changing it means `make perf-baseline`.
const std::vector<SceneCase>& linear_cases() {
  static const std::vector<SceneCase> c = {
      {"cloth_hang/r16", "cloth_hang", {"resolution=16"}},
      {"cloth_hang/r48", "cloth_hang", {"resolution=48"}},
      {"bar_hang/r3", "bar_hang", {"resolution=3"}},
      {"bar_hang/r4", "bar_hang", {"resolution=4"}},
  };
  return c;
}
const std::vector<SceneCase>& sim_cases() {
  static const std::vector<SceneCase> c = {
      {"cloth_hang/r16", "cloth_hang", {"resolution=16", "frames=2", "max_iterations=50"}},
      {"bar_hang/r3", "bar_hang", {"resolution=3", "frames=1", "max_iterations=50"}},
  };
  return c;
}
// The system captured from each linear case: the first of frame 1, after a whole frame of
// cholmod steps, so the cloth is deformed (frame 0's first step already converges the cloth).
constexpr int capture_frame = 1, capture_iteration = 0;

// A statistic that a solver reports and that is deterministic: gated.
std::string stat_kind(const std::string& key) {
  if (key == "levels") return "levels";
  if (key == "operator_complexity") return "operator_complexity";
  if (key == "grid_complexity") return "grid_complexity";
  return "";
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\', o += ch;
    else if (ch == '\n') o += "\\n";
    else if (static_cast<unsigned char>(ch) < 0x20) o += ' ';
    else o += ch;
  }
  return o;
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}

// Metrics in insertion order: name → (kind, JSON value).
struct MetricSet {
  std::vector<std::string> lines;
  void add(const std::string& name, const std::string& kind, double v) { entry(name, kind, num(v)); }
  void add_text(const std::string& name, const std::string& kind, const std::string& v) {
    std::string quoted = "\"";
    quoted += json_escape(v);
    quoted += '"';
    entry(name, kind, quoted);
  }
  void entry(const std::string& name, const std::string& kind, const std::string& value_json) {
    std::string line = "\"";  // built in place: GCC 12 warns (-Wrestrict, falsely) on "\"" + s
    line += json_escape(name);
    line += "\": {\"kind\": \"" + kind + "\", \"value\": " + value_json + "}";
    lines.push_back(std::move(line));
  }
};

bool wanted(const std::vector<std::string>& only, const std::string& m) {
  return only.empty() || std::find(only.begin(), only.end(), m) != only.end();
}

std::vector<std::string> g_cases;  // --cases: empty = all

void linear_metrics(const std::vector<std::string>& sets, const std::vector<std::string>& only, MetricSet& out) {
  const auto solvers = xb::perf::available_linear_solvers();
  for (const auto& c : linear_cases()) {
    if (!wanted(g_cases, c.label)) continue;
    const auto sys = xb::perf::capture_case(c, capture_frame, capture_iteration, sets);
    const std::string base = "linear/" + sys.label;
    out.add(base + "/rows", "size", static_cast<double>(sys.A.rows()));
    out.add(base + "/nonzeros", "size", static_cast<double>(sys.A.nonZeros()));
    const xb::Params p = xb::perf::case_params(c, sets);
    for (const auto& name : solvers) {
      if (!wanted(only, name)) continue;
      const std::string key = base + "/" + name;
      std::cerr << "perf metrics: " << key << "\n";
      try {
        auto solver = xb::make_linear_solver(name, p);
        solver->setup(sys.A, xb::SetupKind::Structure, xb::SetupContext{});
        xb::Vector x;
        const xb::LinearStats st = solver->solve(sys.b, x);
        out.add_text(key + "/status", "status", xb::to_string(st.status));
        if (!st.message.empty()) out.add_text(key + "/message", "info", st.message);
        out.add(key + "/iterations", "iterations", st.iterations);
        out.add(key + "/final_relative_residual", "info", st.final_relative_residual);
        for (const auto& [k, v] : solver->statistics()) {
          const std::string kind = stat_kind(k);
          out.add(key + "/" + k, kind.empty() ? "info" : kind, v);
        }
      } catch (const std::exception& e) {
        out.add_text(key + "/status", "status", std::string("error: ") + e.what());
      }
    }
  }
}

void sim_metrics(const std::vector<std::string>& sets, const std::vector<std::string>& only, MetricSet& out) {
  std::vector<std::string> all = xb::perf::local_methods();
  for (const auto& s : xb::perf::available_linear_solvers()) all.push_back(s);
  for (const auto& c : sim_cases()) {
    if (!wanted(g_cases, c.label)) continue;
    const xb::Params p = xb::perf::case_params(c, sets);
    const xb::Problem prob = xb::build_problem(p);
    for (const auto& method : all) {
      if (!wanted(only, method)) continue;
      const std::string key = "sim/" + c.label + "/" + method;
      std::cerr << "perf metrics: " << key << "\n";
      const xb::RunResult res = xb::run_simulation(prob, p, method);
      out.add_text(key + "/status", "status", res.status);
      if (!res.message.empty()) out.add_text(key + "/message", "info", res.message);
      const double substeps = std::max(1, res.substeps_total);
      out.add(key + "/outer_iterations_per_substep", "outer_iterations", res.outer_iterations / substeps);
      out.add(key + "/relative_dual_residual", "info", res.relative_dual_residual);
      const auto& info = *xb::find_method(method);
      if (!info.local) {
        long long lin = 0;
        for (auto v : res.log.linear_iterations) lin += v;
        out.add(key + "/linear_iterations_per_outer", "iterations",
                res.outer_iterations > 0 ? static_cast<double>(lin) / res.outer_iterations : 0.0);
      }
      for (const auto& [k, v] : res.stats) {
        const std::string kind = stat_kind(k);
        if (!kind.empty()) out.add(key + "/" + k, kind, v);
      }
    }
  }
}

int run(int argc, char** argv) {
  xb::Args args("xb_perf_metrics", std::vector<std::string>(argv + 1, argv + argc),
                {{"--set", true, true}, {"--methods"}, {"--only"}, {"--cases"}, {"--threads"}, {"--out"}});
  const std::vector<std::string> sets = args.all("--set");
  const std::vector<std::string> only = xb::split_list(args.get("--methods", ""));
  for (const auto& m : only)
    if (!xb::find_method(m)) throw xb::Error("xb_perf_metrics: unknown method '" + m + "' in --methods");
  g_cases = xb::split_list(args.get("--cases", ""));
  for (const auto& l : g_cases) {
    bool known = false;
    for (const auto& c : linear_cases()) known |= c.label == l;
    for (const auto& c : sim_cases()) known |= c.label == l;
    if (!known) throw xb::Error("xb_perf_metrics: unknown case '" + l + "' in --cases");
  }
  const std::string part = args.get("--only", "all");
  if (part != "all" && part != "linear" && part != "sim")
    throw xb::Error("xb_perf_metrics: --only must be linear or sim, not '" + part + "'");
  const int threads = args.get_int("--threads", 1);
  if (threads < 1) throw xb::Error("xb_perf_metrics: --threads must be >= 1");
  omp_set_num_threads(threads);
  std::vector<std::string> all_sets = sets;
  all_sets.push_back("threads=" + std::to_string(threads));  // the stepper applies it too
  for (const auto& s : sets) (void)xb::perf::case_params(linear_cases()[0], {s});  // bad key → error now

  MetricSet m;
  if (part != "sim") linear_metrics(all_sets, only, m);
  if (part != "linear") sim_metrics(all_sets, only, m);

  std::ostringstream js;
  js << "{\n  \"threads\": " << threads << ",\n  \"sets\": [";
  for (size_t i = 0; i < sets.size(); ++i) js << (i ? ", " : "") << "\"" << json_escape(sets[i]) << "\"";
  js << "],\n  \"unavailable_methods\": [";
  const auto un = xb::perf::unavailable_methods();
  for (size_t i = 0; i < un.size(); ++i) js << (i ? ", " : "") << "\"" << json_escape(un[i]) << "\"";
  js << "],\n  \"metrics\": {\n";
  for (size_t i = 0; i < m.lines.size(); ++i) js << "    " << m.lines[i] << (i + 1 < m.lines.size() ? ",\n" : "\n");
  js << "  }\n}\n";
  if (args.has("--out")) {
    std::ofstream f(args.get("--out"));
    if (!f) throw xb::Error("xb_perf_metrics: cannot write " + args.get("--out"));
    f << js.str();
  } else {
    std::cout << js.str();
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    rc = run(argc, argv);
  } catch (const xb::Error& e) {
    std::cerr << e.what() << "\n";
    rc = 2;
  } catch (const std::exception& e) {
    std::cerr << "xb_perf_metrics: internal error: " << e.what() << "\n";
    rc = 3;
  }
  MPI_Finalize();
  return rc;
}
