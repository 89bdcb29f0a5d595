// xb_bench: Google Benchmark of the linear level on one captured dual system of at
// least 50,000 rows: mgpbd's setup, values refresh, one V-cycle and full solve, with cholmod
// and cg (and jacobi-pcg) full solves in the same run, all under one clock (wall time: the
// kernels are OpenMP-parallel).
//
//   xb_bench [--xb_system=PREFIX.h5] [--xb_scene=NAME] [--xb_set=key=value]... [--xb_frame=F]
//            [--xb_iteration=I] [--xb_min_rows=N] [--xb_mode=bench|units|smoothers]
//            [--xb_budget=SECONDS] [--xb_units_json=PATH] [--xb_clock=wall|cpu] [Google Benchmark flags...]
// Without --xb_system the system is captured in-process (like `xpbd-bench capture`) from
// cloth_hang at resolution 160 (77,120 rows), frame 2, outer iteration 1. --xb_set applies to
// the scene when capturing and to the solvers (e.g. --xb_set=amg.smoother=jacobi, linear.tol=1e-6).
// --xb_mode=units: instead of the benchmarks, the kernel table of bench/kernel_units.hpp (fill,
// refresh, V-cycle, PCG iteration in SpMV units, both forms; --xb_budget seconds per kernel);
// --xb_mode=smoothers: the smoother cost-per-digit table. Not a ctest: it takes minutes.
#include "../harness/cli/run_setup.hpp"
#include "../harness/cli/wait_policy.hpp"
#include "../harness/sim/capture.hpp"
#include "../harness/io/system_io.hpp"
#include "../core/error.hpp"
#include "../problems/scene.hpp"
#include "../solvers/kernels.hpp"
#include "../solvers/linear_solver.hpp"
#include "kernel_units.hpp"

#if __has_include("../solvers/amg/hierarchy.hpp")
#include "../solvers/amg/hierarchy.hpp"
#define XB_BENCH_HAVE_AMG 1
#endif

#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

struct Config {
  std::string system, scene = "cloth_hang";
  std::vector<std::string> sets;
  int frame = 2, iteration = 1;
  long min_rows = 50000;
  std::string mode = "bench", units_json, clock = "wall";
  double budget = 0.5;
};

struct System {
  xb::SparseMatrix A;
  xb::Vector b;
  xb::Params p;  // for the solvers
  std::string label;
  xb::CapturedSystem cs;  // with the primal data where the file has it
};

System load(const Config& c) {
  System s;
  if (!c.system.empty()) {
    xb::CapturedSystem cs = xb::read_system_h5(c.system);
    s.A = cs.A;
    s.b = cs.b;
    for (const auto& f : xb::param_fields())
      if (cs.attrs.count(f.key)) xb::set_param(s.p, f.key, xb::attr_text(cs.attrs, f.key), c.system);
    for (const auto& kv : c.sets) xb::apply_set(s.p, kv);
    s.label = c.system;
    s.cs = std::move(cs);
    return s;
  }
  std::vector<std::string> sets{"resolution=160"};
  sets.insert(sets.end(), c.sets.begin(), c.sets.end());
  s.p = xb::resolve_params(c.scene, sets);
  std::cerr << "xb_bench: capturing " << c.scene << " frame " << c.frame << ", iteration " << c.iteration << " ...\n";
  xb::CapturedSystem cs = xb::capture_system(s.p, "cholmod", c.frame, 0, c.iteration);
  s.A = cs.A;
  s.b = cs.b;
  s.label = c.scene;
  s.cs = std::move(cs);
  return s;
}

System* sys = nullptr;

void counters(benchmark::State& st, const xb::LinearStats& ls, const xb::Vector& x) {
  xb::Vector r;
  xb::residual(sys->A, x, sys->b, r);
  st.counters["iterations"] = ls.iterations;
  st.counters["rel_residual"] = xb::norm2(r) / xb::norm2(sys->b);
  st.counters["converged"] = ls.status == xb::LinearStatus::converged;
  st.counters["rows"] = static_cast<double>(sys->A.rows());
}

// Setup (structure) + solve, the whole cost of one linear solve with a fresh solver.
void BM_full_solve(benchmark::State& st, const std::string& name) {
  xb::LinearStats ls;
  xb::Vector x;
  for (auto _ : st) {
    auto s = xb::make_linear_solver(name, sys->p);
    s->setup(sys->A, xb::SetupKind::Structure, xb::SetupContext{});
    ls = s->solve(sys->b, x);
  }
  counters(st, ls, x);
}

// The solve alone, after one setup outside the timed loop.
void BM_solve(benchmark::State& st, const std::string& name) {
  auto s = xb::make_linear_solver(name, sys->p);
  s->setup(sys->A, xb::SetupKind::Structure, xb::SetupContext{});
  xb::LinearStats ls;
  xb::Vector x;
  for (auto _ : st) ls = s->solve(sys->b, x);
  counters(st, ls, x);
}

void BM_mgpbd_setup(benchmark::State& st) {
  auto s = xb::make_linear_solver("mgpbd", sys->p);
  for (auto _ : st) s->setup(sys->A, xb::SetupKind::Structure, xb::SetupContext{});
  const auto stats = s->statistics();
  for (const char* k : {"levels", "operator_complexity", "grid_complexity"})
    if (stats.count(k)) st.counters[k] = stats.at(k);
}

// The lazy-setup path: same pattern, new values (here the same values, the same work).
void BM_mgpbd_refresh(benchmark::State& st) {
  auto s = xb::make_linear_solver("mgpbd", sys->p);
  s->setup(sys->A, xb::SetupKind::Structure, xb::SetupContext{});
  for (auto _ : st) s->setup(sys->A, xb::SetupKind::Values, xb::SetupContext{0, 0, 1});
  if (s->last_setup_action() != "refresh") st.SkipWithError(("mgpbd did " + s->last_setup_action() + ", not refresh").c_str());
}

#ifdef XB_BENCH_HAVE_AMG
void BM_mgpbd_vcycle(benchmark::State& st) {
  xb::amg::Hierarchy h;
  h.setup(sys->A, sys->p.amg);
  xb::Vector x;
  for (auto _ : st) {
    h.vcycle(sys->b, x);
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["levels"] = h.num_levels();
}
#endif

// The bandwidth reference: one SpMV of A.
void BM_spmv(benchmark::State& st) {
  xb::Vector y;
  for (auto _ : st) {
    xb::spmv(sys->A, sys->b, y);
    benchmark::DoNotOptimize(y.data());
  }
  st.counters["nnz"] = static_cast<double>(sys->A.nonZeros());
}

bool take(const char* arg, const char* flag, std::string& value) {
  const size_t n = std::strlen(flag);
  if (std::strncmp(arg, flag, n) != 0 || arg[n] != '=') return false;
  value = arg + n + 1;
  return true;
}

// Our flags into c, the rest (Google Benchmark's) into rest. Throws for a bad value.
void parse_args(int argc, char** argv, Config& c, std::vector<char*>& rest) {
  for (int i = 1; i < argc; ++i) {
    std::string v;
    if (take(argv[i], "--xb_system", v)) c.system = v;
    else if (take(argv[i], "--xb_scene", v)) c.scene = v;
    else if (take(argv[i], "--xb_set", v)) c.sets.push_back(v);
    else if (take(argv[i], "--xb_frame", v)) c.frame = std::stoi(v);
    else if (take(argv[i], "--xb_iteration", v)) c.iteration = std::stoi(v);
    else if (take(argv[i], "--xb_min_rows", v)) c.min_rows = std::stol(v);
    else if (take(argv[i], "--xb_mode", v)) c.mode = v;
    else if (take(argv[i], "--xb_budget", v)) c.budget = std::stod(v);
    else if (take(argv[i], "--xb_units_json", v)) c.units_json = v;
    else if (take(argv[i], "--xb_clock", v)) c.clock = v;
    else rest.push_back(argv[i]);
  }
  if (c.mode != "bench" && c.mode != "units" && c.mode != "smoothers")
    throw std::invalid_argument("--xb_mode must be bench, units or smoothers, not '" + c.mode + "'");
  if (c.clock != "wall" && c.clock != "cpu") throw std::invalid_argument("--xb_clock must be wall or cpu, not '" + c.clock + "'");
}

}  // namespace

int main(int argc, char** argv) {
  xb::ensure_bounded_wait_policy(argv);
  xb::limit_blas_threads();
  Config c;
  std::vector<char*> rest{argv[0]};
  try {
    parse_args(argc, argv, c, rest);
  } catch (const std::exception& e) {
    std::cerr << "xb_bench: bad option: " << e.what() << "\n";
    return 2;
  }
  int rargc = static_cast<int>(rest.size());
  benchmark::Initialize(&rargc, rest.data());
  if (benchmark::ReportUnrecognizedArguments(rargc, rest.data())) return 2;

  System s;
  try {
    s = load(c);
    xb::validate(s.p);
  } catch (const std::exception& e) {
    std::cerr << "xb_bench: " << e.what() << "\n";
    return 2;
  }
  if (s.A.rows() < c.min_rows) {
    std::cerr << "xb_bench: the system has " << s.A.rows() << " rows, fewer than --xb_min_rows=" << c.min_rows << "\n";
    return 2;
  }
  if (s.p.threads > 0) omp_set_num_threads(s.p.threads);
  sys = &s;
  try {
    if (c.mode == "units") {
      xb::bench::kernel_units(s.cs, s.p, c.budget, c.units_json, c.clock == "cpu");
      return 0;
    }
    if (c.mode == "smoothers") {
      xb::bench::smoother_table(s.cs, s.p, std::filesystem::path(s.label).stem().string(), c.clock == "cpu");
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "xb_bench: " << e.what() << "\n";
    return 2;
  }
  benchmark::AddCustomContext("system", s.label);
  benchmark::AddCustomContext("rows", std::to_string(s.A.rows()));
  benchmark::AddCustomContext("nnz", std::to_string(s.A.nonZeros()));
  char tol[32];
  std::snprintf(tol, sizeof tol, "%g", s.p.linear.tol);
  benchmark::AddCustomContext("linear.tol", tol);
  benchmark::AddCustomContext("omp_threads", std::to_string(omp_get_max_threads()));

  auto reg = [](const std::string& name, auto fn) {
    return benchmark::RegisterBenchmark(name.c_str(), fn)->UseRealTime()->Unit(benchmark::kMillisecond);
  };
  reg("spmv", BM_spmv);
  const xb::MethodInfo* mg = xb::find_method("mgpbd");
  if (mg && mg->available) {
    reg("mgpbd/setup", BM_mgpbd_setup);
    reg("mgpbd/refresh", BM_mgpbd_refresh);
#ifdef XB_BENCH_HAVE_AMG
    reg("mgpbd/vcycle", BM_mgpbd_vcycle);
#endif
    reg("mgpbd/solve", [](benchmark::State& st) { BM_solve(st, "mgpbd"); });
    reg("mgpbd/setup+solve", [](benchmark::State& st) { BM_full_solve(st, "mgpbd"); });
  } else {
    std::cerr << "xb_bench: mgpbd is not registered in this build; its benchmarks are left out\n";
  }
  reg("cholmod/setup+solve", [](benchmark::State& st) { BM_full_solve(st, "cholmod"); });
  reg("cholmod/solve", [](benchmark::State& st) { BM_solve(st, "cholmod"); });
  reg("cg/setup+solve", [](benchmark::State& st) { BM_full_solve(st, "cg"); });
  reg("jacobi-pcg/setup+solve", [](benchmark::State& st) { BM_full_solve(st, "jacobi-pcg"); });
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
