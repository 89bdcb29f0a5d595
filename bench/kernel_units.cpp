#include "kernel_units.hpp"

#include "../core/error.hpp"
#include "../harness/sim/primal_solve.hpp"
#include "../problems/dual_system.hpp"
#include "../problems/scene.hpp"
#include "../solvers/amg/hierarchy.hpp"
#include "../solvers/kernels.hpp"
#include "../solvers/timer.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <functional>
#include <memory>
#include <vector>

namespace xb::bench {

namespace {

// The clock of every measurement: wall time, or the process's CPU time (every thread's; with a
// passive wait policy idle threads sleep, so it is the work done), which a loaded machine
// disturbs far less.
bool cpu_clock = false;
double now_s() {
  timespec ts;
  clock_gettime(cpu_clock ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Least time of f in ms (the call least disturbed by other load): one warm-up call, then at
// least 3 calls and until budget_s (wall).
double least_ms(const std::function<void()>& f, double budget_s) {
  f();
  std::vector<double> t;
  Timer total;
  while (t.size() < 3 || (total.seconds() < budget_s && t.size() < 200)) {
    const double t0 = now_s();
    f();
    t.push_back((now_s() - t0) * 1e3);
  }
  return *std::min_element(t.begin(), t.end());
}

// Triad a = b + s·c: bytes per second over 3 streams of n doubles.
double triad_bandwidth(double budget_s) {
  const long n = 1L << 22;
  std::vector<double> a(n), b(n), c(n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) a[i] = 0, b[i] = 1.0 + i % 7, c[i] = 2.0 - i % 5;
  const double ms = least_ms(
      [&] {
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) a[i] = b[i] + 3.0 * c[i];
      },
      budget_s);
  return 3.0 * 8.0 * n / (ms * 1e-3);
}

struct Row {
  std::string form, kernel;
  double ms, units;
  std::string note;
};

struct Table {
  std::vector<Row> rows;
  double spmv_ms = 0;  // the unit of the current form
  void add(const std::string& form, const std::string& kernel, double ms, const std::string& note = "") {
    rows.push_back({form, kernel, ms, ms / spmv_ms, note});
  }
};

// SpMV with A, double and float storage, against the floor 12·nnz + 16·rows (float: 8·nnz + 8·rows).
void spmv_rows(Table& t, const std::string& form, const SparseMatrix& A, double bandwidth, double budget) {
  Vector x = Vector::Ones(A.rows()), y;
  t.spmv_ms = least_ms([&] { spmv(A, x, y); }, budget);
  const double nnz = static_cast<double>(A.nonZeros()), rows = static_cast<double>(A.rows());
  const double floor_ms = (12 * nnz + 16 * rows) / bandwidth * 1e3;
  char note[96];
  std::snprintf(note, sizeof note, "floor %.3f ms: %.2fx", floor_ms, t.spmv_ms / floor_ms);
  t.add(form, "spmv", t.spmv_ms, note);
  // The V-cycle's single-precision storage: the same product on float values.
  CsrOf<float> Af = A.cast<float>();
  VectorOf<float> xf = VectorOf<float>::Ones(A.rows()), yf(A.rows());
  const double f_ms = least_ms(
      [&] {
        const int n = static_cast<int>(Af.rows());
        const int *o = Af.outerIndexPtr(), *c = Af.innerIndexPtr();
        const float* v = Af.valuePtr();
#pragma omp parallel for schedule(static)
        for (int i = 0; i < n; ++i) {
          float s = 0;
          for (int k = o[i]; k < o[i + 1]; ++k) s += v[k] * xf[c[k]];
          yf[i] = s;
        }
      },
      budget);
  const double ffloor = (8 * nnz + 8 * rows) / bandwidth * 1e3;
  std::snprintf(note, sizeof note, "floor %.3f ms: %.2fx", ffloor, f_ms / ffloor);
  t.add(form, "spmv (float)", f_ms, note);
}

// One PCG iteration: capped solves' time over their iterations.
void pcg_iteration_row(Table& t, const std::string& form, const std::string& kernel, LinearSolver& s, const Vector& b,
                       double budget) {
  Vector x;
  int its = 0;
  const double ms = least_ms([&] { its = s.solve(b, x).iterations; }, budget);
  if (its > 0) t.add(form, kernel, ms / its);
}

// Setup, refresh, V-cycle of the hierarchy on A and one PCG iteration of mgpbd, per precision.
void amg_rows(Table& t, const std::string& form, const SparseMatrix& A, const Vector& b, Params p,
              const amg::MatrixInfo& info, double budget) {
  for (const char* precision : {"double", "single"}) {
    p.amg.precision = precision;
    const std::string tag = std::string(" (") + precision + ")";
    amg::AmgOptions opt = p.amg;
    amg::Hierarchy h;
    const double setup_ms = least_ms([&] { h.setup(A, opt, info); }, budget);
    const double refresh_ms = least_ms([&] { h.refresh(A); }, budget);
    Vector x;
    const double vcycle_ms = least_ms([&] { h.vcycle(b, x); }, budget);
    if (std::string(precision) == "double") t.add(form, "amg setup", setup_ms);
    t.add(form, "amg refresh" + tag, refresh_ms);
    t.add(form, "V-cycle" + tag, vcycle_ms, "smoother " + h.options().smoother.kind);
    auto s = make_linear_solver("mgpbd", p);
    s->setup(A, SetupKind::Structure, SetupContext{0, 0, 0, info.block_size, info.near_kernel});
    pcg_iteration_row(t, form, "mgpbd PCG iteration" + tag, *s, b, budget);
  }
  auto j = make_linear_solver("jacobi-pcg", p);
  j->setup(A, SetupKind::Structure, SetupContext{});
  pcg_iteration_row(t, form, "jacobi-pcg iteration", *j, b, budget);
}

// The file's topology as a Problem (what DualSystem reads: each constraint's particles, w). The
// file stores each constraint's slots in ascending particle order, its gradients in the same order,
// which a problem rebuilt from the scene does not share.
Problem topology_of(const ConstraintGraph& g) {
  Problem prob;
  prob.particles.x = Eigen::Matrix3Xd::Zero(3, g.num_particles());
  prob.particles.w = g.w;
  for (const auto& ps : g.particles) {
    if (ps[2] >= 0) prob.tets.idx.push_back(ps);
    else if (prob.tets.idx.empty()) prob.distance.idx.push_back({ps[0], ps[1]});
    else throw Error("a two-particle constraint after a tet (the dual system numbers distances first)");
  }
  return prob;
}

// A's fill from the captured gradients, checked against J M⁻¹ Jᵀ + α̃ by Eigen's sparse products.
void dual_fill_row(Table& t, const CapturedSystem& cs, double budget) {
  if (!cs.has_primal()) {
    t.add("dual", "fill A", NAN, "skipped: the file has no gradients");
    return;
  }
  try {
    const Problem topo = topology_of(cs.graph);
    DualSystem ds(topo);
    ConstraintState state;
    state.grad = cs.grad;
    const double ms = least_ms([&] { ds.fill(state, cs.alpha_tilde); }, budget);
    const SparseMatrix J = jacobian_csr(cs.graph, cs.grad);
    Vector minv(J.cols());
    for (long q = 0; q < cs.graph.w.size(); ++q) minv.segment<3>(3 * q).setConstant(cs.graph.w[q]);
    SparseMatrix Aref = J * minv.asDiagonal() * SparseMatrix(J.transpose());
    Aref.diagonal() += cs.alpha_tilde;
    const double diff = SparseMatrix(ds.A() - Aref).coeffs().cwiseAbs().maxCoeff();
    char note[96];
    std::snprintf(note, sizeof note, "max |A - (J M^-1 J^T + a~)| = %.2g max |A|", diff / Aref.coeffs().cwiseAbs().maxCoeff());
    t.add("dual", "fill A", ms, note);
  } catch (const std::exception& e) {
    t.add("dual", "fill A", NAN, std::string("skipped: ") + e.what());
  }
}

// C and ∇C of every constraint at the captured positions (the problem rebuilt from the file's
// parameters): the step before either fill.
void evaluate_row(Table& t, const CapturedSystem& cs, const Params& p, double budget) {
  try {
    const Problem prob = build_problem(p);
    if (cs.x.cols() != prob.particles.size() || prob.num_constraints() != cs.A.rows()) {
      t.add("dual", "evaluate C, grad C", NAN, "skipped: the rebuilt problem differs from the file's");
      return;
    }
    ConstraintState state;
    t.add("dual", "evaluate C, grad C", least_ms([&] { evaluate_constraints(prob, cs.x, state); }, budget));
  } catch (const std::exception& e) {
    t.add("dual", "evaluate C, grad C", NAN, std::string("skipped: ") + e.what());
  }
}

void write_json(const Table& t, const std::string& path, double bandwidth) {
  std::ofstream f(path);
  f << "{\"triad_bytes_per_s\": " << bandwidth << ", \"clock\": \"" << (cpu_clock ? "cpu" : "wall")
    << "\", \"threads\": " << omp_get_max_threads() << ", \"rows\": [";
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const Row& r = t.rows[i];
    f << (i ? ",\n " : "\n ") << "{\"form\": \"" << r.form << "\", \"kernel\": \"" << r.kernel << "\", \"ms\": "
      << (std::isfinite(r.ms) ? r.ms : -1) << ", \"spmv_units\": " << (std::isfinite(r.units) ? r.units : -1) << "}";
  }
  f << "]}\n";
}

}  // namespace

void kernel_units(const CapturedSystem& cs, const Params& p0, double budget, const std::string& json_path, bool cpu) {
  cpu_clock = cpu;
  Params p = p0;
  p.linear.max_iterations = std::min(p.linear.max_iterations, 20);  // iteration cost, not convergence
  const double bandwidth = triad_bandwidth(budget);
  Table t;
  spmv_rows(t, "dual", cs.A, bandwidth, budget);
  dual_fill_row(t, cs, budget);
  evaluate_row(t, cs, p, budget);
  amg_rows(t, "dual", cs.A, cs.b, p, {}, budget);
  if (cs.has_primal()) {
    PrimalSystem ps(cs.graph);
    ps.fill(cs.grad, cs.alpha_tilde);
    Vector f;
    ps.rhs(cs.grad, cs.alpha_tilde, cs.b, f);
    const Eigen::MatrixXd B = ps.rigid_modes(cs.x);
    spmv_rows(t, "primal", ps.K(), bandwidth, budget);
    t.add("primal", "fill K", least_ms([&] { ps.fill(cs.grad, cs.alpha_tilde); }, budget));
    amg_rows(t, "primal", ps.K(), f, p, {3, &B}, budget);
  }
  std::printf("triad %.2f GB/s (%s time), %d threads; SpMV unit = one product with the form's matrix\n\n",
              bandwidth * 1e-9, cpu ? "CPU" : "wall", omp_get_max_threads());
  std::printf("| form | kernel | ms | SpMV units | note |\n|---|---|---|---|---|\n");
  for (const Row& r : t.rows)
    std::printf("| %s | %s | %.3f | %.2f | %s |\n", r.form.c_str(), r.kernel.c_str(), r.ms, r.units, r.note.c_str());
  if (!json_path.empty()) write_json(t, json_path, bandwidth);
}

void smoother_table(const CapturedSystem& cs, const Params& p, const std::string& label, bool cpu) {
  cpu_clock = cpu;
  std::printf("| system | form | smoother | sweeps | degree | setup s | solve s | iterations | rel. residual | solve s per decade | total s per decade |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Variant {
    std::string kind;
    int sweeps, degree;  // degree: Chebyshev kinds only (0 elsewhere)
  };
  for (const std::string form : {"dual", "primal"}) {
    if (form == "primal" && !cs.has_primal()) continue;
    std::vector<std::string> kinds = {"jacobi", "chebyshev", "gs"};
    if (form == "primal") kinds.insert(kinds.end(), {"block_jacobi", "block_chebyshev", "block_gs"});
    // Dual: one sweep (its default), Chebyshev of degree 2–4. Primal: one and two sweeps, the
    // Chebyshev kinds at degree 3 and, once, 4 and 5 (the default is degree 4 once).
    std::vector<Variant> variants;
    for (const auto& kind : kinds) {
      const bool cheb = kind.find("chebyshev") != std::string::npos;
      if (form == "dual") {
        for (int d : cheb ? std::vector<int>{2, 3, 4} : std::vector<int>{0}) variants.push_back({kind, 1, d});
      } else {
        variants.push_back({kind, 1, cheb ? 3 : 0});
        variants.push_back({kind, 2, cheb ? 3 : 0});
        if (cheb) variants.insert(variants.end(), {{kind, 1, 4}, {kind, 1, 5}});
      }
    }
    for (const auto& [kind, sweeps, degree] : variants) {
      Params q = p;
      q.amg.smoother.kind = kind;
      q.amg.smoother.sweeps = sweeps;
      q.amg.smoother.degree = degree;  // 0 (not a Chebyshev kind): auto, unused
      const std::string deg = degree ? std::to_string(degree) : "-";
      double setup = 0, solve = 0, rel = NAN;
      int its = 0;
      try {
        if (form == "dual") {
          auto s = make_linear_solver("mgpbd", q);
          double t0 = now_s();
          s->setup(cs.A, SetupKind::Structure, SetupContext{});
          setup = now_s() - t0;
          Vector x;
          t0 = now_s();
          const LinearStats st = s->solve(cs.b, x);
          solve = now_s() - t0, its = st.iterations;
          Vector r;
          residual(cs.A, x, cs.b, r);
          rel = norm2(r) / norm2(cs.b);
        } else {
          PrimalSolve ps(make_linear_solver("mgpbd", q), cs.graph, q.linear);
          double t0 = now_s();
          ps.setup(cs.grad, cs.alpha_tilde, cs.x, SetupKind::Structure, SetupContext{});
          setup = now_s() - t0;
          Vector dl;
          t0 = now_s();
          const LinearStats st = ps.solve(cs.b, dl);
          solve = now_s() - t0, its = st.iterations, rel = st.final_relative_residual;
        }
      } catch (const std::exception& e) {
        std::printf("| %s | %s | %s | %d | %s | failed: %s |\n", label.c_str(), form.c_str(), kind.c_str(), sweeps,
                    deg.c_str(), e.what());
        continue;
      }
      const double decades = -std::log10(rel);
      std::printf("| %s | %s | %s | %d | %s | %.3f | %.3f | %d | %.1e | %.3f | %.3f |\n", label.c_str(), form.c_str(),
                  kind.c_str(), sweeps, deg.c_str(), setup, solve, its, rel, solve / decades, (setup + solve) / decades);
      std::fflush(stdout);
    }
  }
}

}  // namespace xb::bench
