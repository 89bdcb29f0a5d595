// xb_microbench: the timed half of CI performance tracking, in Google Benchmark.
// Kernels: assembly of A (evaluate_constraints + DualSystem::fill), SpMV, one outer iteration of
// each local method, setup (structure and values) and a full solve of a captured system by every
// registered linear solver, and — where solvers/amg is built — one sweep of each smoother, one
// V-cycle, and the AMG hierarchy's setup and values refresh. Sizes run from ~800 rows to ~77K
// rows (cloth_hang at resolution 160). A STREAM-like triad runs in the same process so that
// scripts/perf.py can read every time as a ratio to the memory-bandwidth reference.
//
//   xb_microbench [--xb_sizes=small|all] [Google Benchmark flags...]
// Google Benchmark reports wall-clock and the benchmark thread's CPU time. scripts/perf.py runs
// this single-threaded (OMP_NUM_THREADS=1) by default and reads CPU time, which a loaded shared
// machine disturbs far less than wall-clock time of spinning OpenMP teams.
#include "../harness/perf/perf_common.hpp"

#include "../problems/dual_system.hpp"
#include "../core/error.hpp"
#include "../problems/scene.hpp"
#include "../solvers/kernels.hpp"
#include "../solvers/linear_solver.hpp"
#include "../solvers/local/xpbd_local.hpp"

#if __has_include("../solvers/amg/hierarchy.hpp")
#include "../solvers/amg/hierarchy.hpp"
#include "../solvers/amg/relaxation/smoothers.hpp"
#define XB_BENCH_AMG 1
#endif

#include <benchmark/benchmark.h>
#include <mpi.h>
#include <omp.h>

#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <vector>

namespace {

using xb::perf::SceneCase;

// small: the CI gate's short form; all: up to >= 50K rows.
const std::vector<SceneCase> small_cases = {
    {"cloth_hang/r16", "cloth_hang", {"resolution=16"}},
    {"bar_hang/r3", "bar_hang", {"resolution=3"}},
};
const std::vector<SceneCase> large_cases = {
    {"cloth_hang/r64", "cloth_hang", {"resolution=64"}},
    {"bar_hang/r6", "bar_hang", {"resolution=6"}},
    {"cloth_hang/r160", "cloth_hang", {"resolution=160"}},
};

// Everything a benchmark of one scene needs, built once per process (not timed).
struct Case {
  xb::Params p;
  std::unique_ptr<xb::Problem> prob;
  std::unique_ptr<xb::DualSystem> ds;
  Eigen::Matrix3Xd x_pred;
  Eigen::VectorXd alpha_tilde;
  xb::ConstraintState state;
  xb::perf::LabelledSystem sys;  // the first system of frame 1 (after a frame of cholmod steps)
};

Case& get_case(const SceneCase& c) {
  static std::map<std::string, std::unique_ptr<Case>> cache;
  auto& slot = cache[c.label];
  if (!slot) {
    auto k = std::make_unique<Case>();
    k->p = xb::perf::case_params(c, {});
    k->prob = std::make_unique<xb::Problem>(xb::build_problem(k->p));
    k->ds = std::make_unique<xb::DualSystem>(*k->prob);
    const double h = k->p.dt / k->p.substeps;
    const auto& P = k->prob->particles;
    k->x_pred = P.x;
    for (int i = 0; i < P.size(); ++i)
      if (P.w[i] > 0) k->x_pred.col(i) += h * (P.v.col(i) + h * k->prob->gravity);  // the stepper's prediction
    k->alpha_tilde = xb::scaled_compliance(*k->prob, h);
    xb::evaluate_constraints(*k->prob, k->x_pred, k->state);
    k->sys = xb::perf::capture_case(c, 1, 0, {});
    slot = std::move(k);
  }
  return *slot;
}

void set_rows(benchmark::State& st, const xb::SparseMatrix& A) {
  st.counters["rows"] = static_cast<double>(A.rows());
  st.counters["nonzeros"] = static_cast<double>(A.nonZeros());
}

// a = b + s·c over n doubles: 3 streams of 8 bytes per element (no write-allocate counted).
void bm_triad(benchmark::State& st, long n) {
  std::vector<double> a(n), b(n), c(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) a[i] = 0, b[i] = 1.0 + i % 7, c[i] = 2.0 - i % 5;  // first touch in parallel
  const double s = 3.0;
  for (auto _ : st) {
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  st.SetBytesProcessed(st.iterations() * 3 * n * static_cast<long>(sizeof(double)));
}

void bm_assembly(benchmark::State& st, SceneCase c) {
  Case& k = get_case(c);
  for (auto _ : st) {
    xb::evaluate_constraints(*k.prob, k.x_pred, k.state);
    k.ds->fill(k.state, k.alpha_tilde);
    benchmark::ClobberMemory();
  }
  set_rows(st, k.ds->A());
}

void bm_spmv(benchmark::State& st, SceneCase c) {
  Case& k = get_case(c);
  xb::Vector y(k.sys.A.rows());
  for (auto _ : st) {
    xb::spmv(k.sys.A, k.sys.b, y);
    benchmark::DoNotOptimize(y.data());
  }
  set_rows(st, k.sys.A);
}

// One outer iteration of a local method: constraints at x, then one sweep (as the stepper does).
void bm_local(benchmark::State& st, std::string method, SceneCase c) {
  Case& k = get_case(c);
  xb::LocalMethod local(*k.prob, *k.ds, k.p.xpbd, method == "xpbd-gs");
  Eigen::Matrix3Xd x = k.x_pred;
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(k.prob->num_constraints());
  xb::ConstraintState s;
  for (auto _ : st) {
    xb::evaluate_constraints(*k.prob, x, s);
    local.sweep(x, lambda, k.alpha_tilde, s);
    benchmark::ClobberMemory();
  }
  set_rows(st, k.ds->A());
}

void bm_setup(benchmark::State& st, std::string solver, SceneCase c, xb::SetupKind kind) {
  Case& k = get_case(c);
  auto s = xb::make_linear_solver(solver, k.p);
  s->setup(k.sys.A, xb::SetupKind::Structure, xb::SetupContext{});
  int it = 0;
  for (auto _ : st) {
    // Values: iteration > 0 of the same frame, so lazy policies refresh rather than rebuild.
    s->setup(k.sys.A, kind, xb::SetupContext{0, 0, ++it});
    benchmark::ClobberMemory();
  }
  set_rows(st, k.sys.A);
}

// A full solve to linear.tol from zero (setup done once, outside the timing).
void bm_solve(benchmark::State& st, std::string solver, SceneCase c) {
  Case& k = get_case(c);
  auto s = xb::make_linear_solver(solver, k.p);
  s->setup(k.sys.A, xb::SetupKind::Structure, xb::SetupContext{});
  xb::Vector x;
  xb::LinearStats ls;
  for (auto _ : st) {
    ls = s->solve(k.sys.b, x);
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["solver_iterations"] = ls.iterations;
  st.counters["relative_residual"] = ls.final_relative_residual;
  if (ls.status != xb::LinearStatus::converged) st.SetLabel(xb::to_string(ls.status));
  set_rows(st, k.sys.A);
}

#ifdef XB_BENCH_AMG
// One sweep (sweeps = 1) of a smoother on level 0, from a non-zero x.
void bm_smoother(benchmark::State& st, std::string kind, SceneCase c) {
  Case& k = get_case(c);
  xb::amg::SmootherOptions o;
  o.kind = kind;
  o.sweeps = 1;
  auto sm = xb::amg::make_smoother(o, k.sys.A);
  xb::Vector x = xb::Vector::Zero(k.sys.A.rows());
  for (auto _ : st) {
    sm->presmooth(k.sys.A, k.sys.b, x, false);
    benchmark::DoNotOptimize(x.data());
  }
  set_rows(st, k.sys.A);
}

void bm_vcycle(benchmark::State& st, SceneCase c) {
  Case& k = get_case(c);
  xb::amg::Hierarchy h;
  h.setup(k.sys.A, k.p.amg);
  xb::Vector x;
  for (auto _ : st) {
    h.vcycle(k.sys.b, x);
    benchmark::DoNotOptimize(x.data());
  }
  st.counters["levels"] = h.num_levels();
  set_rows(st, k.sys.A);
}

void bm_amg_setup(benchmark::State& st, SceneCase c, bool refresh) {
  Case& k = get_case(c);
  xb::amg::Hierarchy h;
  const auto opt = k.p.amg;
  h.setup(k.sys.A, opt);
  for (auto _ : st) {
    if (refresh)
      h.refresh(k.sys.A);
    else
      h.setup(k.sys.A, opt);
    benchmark::ClobberMemory();
  }
  st.counters["levels"] = h.num_levels();
  st.counters["operator_complexity"] = h.operator_complexity();
  set_rows(st, k.sys.A);
}
#endif

// A benchmark that throws (a solver error) is reported as skipped with the message, and the
// run goes on.
template <class F>
void reg(const std::string& name, F f) {
  benchmark::RegisterBenchmark(name.c_str(),
                               [f](benchmark::State& st) {
                                 try {
                                   f(st);
                                 } catch (const std::exception& e) {
                                   st.SkipWithError(e.what());
                                 }
                               })
      ->Unit(benchmark::kMillisecond);
}

void register_all(bool all_sizes) {
  reg("triad/n:8388608", [](benchmark::State& st) { bm_triad(st, 1L << 23); });
  std::vector<SceneCase> cases = small_cases;
  if (all_sizes) cases.insert(cases.end(), large_cases.begin(), large_cases.end());
  const auto solvers = xb::perf::available_linear_solvers();  // the registry: new solvers appear here
  for (const auto& c : cases) {
    reg("assembly/" + c.label, [c](benchmark::State& st) { bm_assembly(st, c); });
    reg("spmv/" + c.label, [c](benchmark::State& st) { bm_spmv(st, c); });
    for (const auto& m : xb::perf::local_methods())
      reg("outer_iteration/" + m + "/" + c.label, [m, c](benchmark::State& st) { bm_local(st, m, c); });
#ifdef XB_BENCH_AMG
    for (const std::string kind : {"jacobi", "chebyshev", "gs"})
      reg("amg_smoother/" + kind + "/" + c.label, [kind, c](benchmark::State& st) { bm_smoother(st, kind, c); });
    reg("amg_vcycle/" + c.label, [c](benchmark::State& st) { bm_vcycle(st, c); });
    reg("amg_setup/" + c.label, [c](benchmark::State& st) { bm_amg_setup(st, c, false); });
    reg("amg_refresh/" + c.label, [c](benchmark::State& st) { bm_amg_setup(st, c, true); });
#endif
    for (const auto& s : solvers) {
      reg("setup_structure/" + s + "/" + c.label,
          [s, c](benchmark::State& st) { bm_setup(st, s, c, xb::SetupKind::Structure); });
      reg("setup_values/" + s + "/" + c.label,
          [s, c](benchmark::State& st) { bm_setup(st, s, c, xb::SetupKind::Values); });
      reg("solve/" + s + "/" + c.label, [s, c](benchmark::State& st) { bm_solve(st, s, c); });
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    // Our own flag first (Google Benchmark rejects flags it does not know).
    bool all_sizes = true;
    std::vector<char*> rest;
    for (int i = 0; i < argc; ++i) {
      if (!std::strncmp(argv[i], "--xb_sizes=", 11)) {
        const std::string v = argv[i] + 11;
        if (v != "small" && v != "all") throw xb::Error("xb_microbench: --xb_sizes must be small or all, not '" + v + "'");
        all_sizes = v == "all";
      } else {
        rest.push_back(argv[i]);
      }
    }
    int n = static_cast<int>(rest.size());
    benchmark::Initialize(&n, rest.data());
    if (benchmark::ReportUnrecognizedArguments(n, rest.data())) {
      rc = 2;
    } else {
      register_all(all_sizes);
      benchmark::RunSpecifiedBenchmarks();
      benchmark::Shutdown();
    }
  } catch (const std::exception& e) {
    std::cerr << "xb_microbench: " << e.what() << "\n";
    rc = 2;
  }
  MPI_Finalize();
  return rc;
}
