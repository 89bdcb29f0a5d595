// The linear level of the benchmark: `capture` writes the dual system (A, b) of one outer
// iteration of a scene to disk; `solve` runs linear solvers on a captured system and records
// their residual histories and their error against the direct (CHOLMOD) solution.
#include "args.hpp"
#include "commands.hpp"
#include "../sim/capture.hpp"
#include "../sim/primal_solve.hpp"
#include "report.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "run_setup.hpp"
#include "../io/run_record.hpp"
#include "../io/system_io.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/kernels.hpp"
#include "../../solvers/linear_solver.hpp"
#include "../../solvers/timer.hpp"

#include <omp.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <new>
#include <set>

namespace fs = std::filesystem;

namespace xb {

namespace {

constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();

int require_int(const Args& args, const std::string& cmd, const std::string& flag) {
  if (!args.has(flag)) throw Error(cmd + ": option " + flag + " is required");
  return args.get_int(flag, 0);
}

std::string strip_h5(const std::string& s) {
  return s.size() > 3 && s.compare(s.size() - 3, 3, ".h5") == 0 ? s.substr(0, s.size() - 3) : s;
}

// max |A_ij − A_ji| / max |A_ij|: the assembly sums shared-particle terms in row order, so the
// two triangles may differ in the last bits; Matrix Market keeps the lower one.
double asymmetry(const SparseMatrix& A) {
  const SparseMatrix At = A.transpose();
  const double scale = A.coeffs().size() ? A.coeffs().cwiseAbs().maxCoeff() : 0.0;
  const SparseMatrix D = A - At;
  const double d = D.coeffs().size() ? D.coeffs().cwiseAbs().maxCoeff() : 0.0;
  return scale > 0 ? d / scale : 0.0;
}

// The parameters a system was captured with (its attributes), so that solvers see the scene's
// settings; keys this build does not know are ignored.
Params params_from_system(const CapturedSystem& sys, const std::string& path) {
  Params p;
  for (const auto& f : param_fields()) {
    if (!sys.attrs.count(f.key)) continue;
    set_param(p, f.key, attr_text(sys.attrs, f.key), path + " (attribute " + f.key + ")");
  }
  return p;
}

// ‖v‖_A = sqrt(vᵀAv).
double a_norm(const SparseMatrix& A, const Vector& v) {
  Vector Av;
  spmv(A, v, Av);
  const double q = dot(v, Av);
  return q >= 0 ? std::sqrt(q) : nan_value;
}

// Every file capture may write: none an input, none a results file (capture never replaces one).
void check_capture_outputs(const std::string& prefix, const std::string& scene, const Params& p) {
  std::error_code ec;
  if (fs::path(prefix).filename().empty() || fs::is_directory(prefix, ec))  // "dir/" would write dir/.h5, dir/_A.mtx
    throw Error("capture: --out " + prefix + " is a directory; give a file prefix (PREFIX.h5, PREFIX_A.mtx, ...)");
  std::vector<std::string> inputs = mesh_inputs(p);
  inputs.push_back(resolve_scene(scene));
  for (const char* suffix : {".h5", "_A.mtx", "_b.mtx", "_K.mtx", "_f.mtx"}) {
    const std::string f = prefix + suffix;
    check_output("capture", "--out", f, inputs);
    if (is_results_file(f)) throw Error("capture: --out " + prefix + " would replace " + f + ", a results file (it holds /runs)");
  }
}

}  // namespace

int cmd_capture(const CommandArgs& argv) {
  Args args("capture", argv,
            {{"--scene"}, {"--set", true, true}, {"--frame"}, {"--substep"}, {"--iteration"}, {"--out"}, {"--solver"}, {"--time-budget"}, {"--quiet", false}});
  // Everything is checked before anything runs or is written.
  const std::string scene = args.require("--scene");
  const std::string prefix = strip_h5(args.require("--out"));
  const int frame = require_int(args, "capture", "--frame");
  const int iteration = require_int(args, "capture", "--iteration");
  const int substep = args.get_int("--substep", 0);
  if (frame < 0 || frame >= max_frames)
    throw Error("capture: --frame " + std::to_string(frame) + " is out of range [0, " + std::to_string(max_frames - 1) + "]");
  if (iteration < 0) throw Error("capture: --iteration must be >= 0");
  const auto solvers = parse_methods(args.get("--solver", "cholmod"), true);
  if (solvers.size() != 1) throw Error("capture: --solver takes one linear solver (it drives the simulation)");
  const std::string& solver = solvers[0];
  Params p = resolve_params(scene, args.all("--set"));
  if (substep < 0 || substep >= p.substeps)
    throw Error("capture: --substep " + std::to_string(substep) + " out of range [0, " + std::to_string(p.substeps - 1) + "]");
  if (iteration >= p.max_iterations)
    throw Error("capture: --iteration " + std::to_string(iteration) + " is never assembled: the stepper stops at max_iterations = " +
                std::to_string(p.max_iterations) + " (raise it with --set max_iterations=N)");
  check_capture_outputs(prefix, scene, p);
  check_capturable(p);  // before the progress line: the refusal is the one line on stderr
  const double budget = time_budget_flag(args, "capture");
  const std::string head = "capture: " + p.scene + " with " + solver + " to frame " + std::to_string(frame) + ", substep " +
                           std::to_string(substep) + ", iteration " + std::to_string(iteration) + " ...";
  std::cerr << head << std::flush;
  CapturedSystem sys;
  try {
    ProgressLine line(progress_wanted(args), head);
    sys = capture_system(p, solver, frame, substep, iteration, budget,
                         [&line](const IterationProgress& s) { line.set_iteration(s); });
  } catch (const Error&) {
    std::cerr << "\n";
    throw;
  }
  std::cerr << " captured\n";

  RunRecord meta;  // for its attributes: provenance and every parameter
  add_provenance(meta, p);
  meta.attrs["scene"] = p.scene;
  meta.attrs["frame"] = static_cast<long long>(frame);
  meta.attrs["substep"] = static_cast<long long>(substep);
  meta.attrs["iteration"] = static_cast<long long>(iteration);
  meta.attrs["capture_solver"] = solver;
  meta.attrs["rhs_norm"] = sys.b.norm();  // = the dual residual ‖C + α̃λ‖ at that state
  meta.attrs["asymmetry"] = asymmetry(sys.A);
  sys.attrs = meta.attrs;
  std::string files;
  std::vector<std::string> written;
  try {
    written = write_captured_system(prefix, sys);
  } catch (const WriteError& e) {
    throw WriteError(e.path, e.err, std::string("capture: ") + e.what());
  }
  for (const auto& f : written) files += (files.empty() ? "" : ", ") + f;
  std::cout << "capture: wrote " << files << " (" << sys.A.rows() << " rows, " << sys.A.nonZeros() << " non-zeros)\n";
  return 0;
}

namespace {

// The reference x* = A⁻¹b: CHOLMOD plus one step of iterative refinement (empty x if it failed).
struct DirectReference {
  Vector x;
  std::string status = "ok";
  double relative_residual = nan_value;
  double a_norm = nan_value, l2_norm = nan_value;
};

DirectReference direct_reference(const SparseMatrix& A, const Vector& b, const Params& p) {
  DirectReference ref;
  try {
    auto direct = make_linear_solver("cholmod", p);
    direct->setup(A, SetupKind::Structure, SetupContext{});
    const LinearStats st = direct->solve(b, ref.x);
    if (st.status != LinearStatus::converged) {
      ref.status = to_string(st.status);
      ref.x.resize(0);
    } else {
      Vector r, d;
      residual(A, ref.x, b, r);
      if (direct->solve(r, d).status == LinearStatus::converged) ref.x += d;
      residual(A, ref.x, b, r);
      ref.relative_residual = norm2(b) > 0 ? norm2(r) / norm2(b) : 0;
    }
  } catch (const std::exception& e) {
    ref.status = std::string("error: ") + e.what();
    ref.x.resize(0);
  }
  if (ref.x.size() == 0) {
    std::cerr << "solve: no direct reference solution (cholmod: " << ref.status << "); error_vs_direct is NaN\n";
  } else {
    ref.a_norm = a_norm(A, ref.x);
    ref.l2_norm = norm2(ref.x);
  }
  return ref;
}

// What one solver did on the system, timed by the harness.
struct SolveOutcome {
  std::string status = "error", message;
  LinearStats st;
  Vector x;
  double setup_time = nan_value, solve_time = nan_value;
  std::map<std::string, double> stats;
  std::map<std::string, std::vector<double>> arrays;
};

// One solver in one form from a fresh instance. A throwing solver is an outcome, not an error.
SolveOutcome solve_one(const CapturedSystem& sys, const std::string& name, const Params& q, const std::string& form) {
  SolveOutcome o;
  try {
    // The solver is constructed outside the clock, as before the form existed; in the primal
    // form K's pattern and values are assembled from J inside the timed setup, as in a simulation.
    auto solver = make_linear_solver(name, q);
    Timer t;
    if (form == "primal") {
      PrimalSolve primal(std::move(solver), sys.graph, q.linear);
      primal.setup(sys.grad, sys.alpha_tilde, sys.x, SetupKind::Structure, SetupContext{});
      o.setup_time = t.seconds();
      t.reset();
      o.st = primal.solve(sys.b, o.x);
      o.solve_time = t.seconds();
      o.stats = primal.solver().statistics();
      o.arrays = primal.solver().array_statistics();
      o.stats["primal_rows"] = primal.system().rows();
      o.stats["primal_nonzeros"] = static_cast<double>(primal.system().K().nonZeros());
    } else {
      solver->setup(sys.A, SetupKind::Structure, SetupContext{});
      o.setup_time = t.seconds();
      t.reset();
      o.st = solver->solve(sys.b, o.x);
      o.solve_time = t.seconds();
      o.stats = solver->statistics();
      o.arrays = solver->array_statistics();
    }
    o.status = o.st.status == LinearStatus::converged ? "ok" : to_string(o.st.status);
    o.message = o.st.message;
  } catch (const std::bad_alloc&) {
    o.status = "error";
    o.message = "out of memory in the " + std::string(std::isnan(o.setup_time) ? "setup" : "solve") + " of " + name +
                " (" + form + " form)";
  } catch (const std::exception& e) {
    o.status = "error";
    o.message = e.what();
  }
  return o;
}

// The outcome into the run record, with the harness's own residual and errors, from x (never
// from what the solver says).
void record_outcome(RunRecord& r, SolveOutcome o, const DirectReference& ref, const SparseMatrix& A, const Vector& b) {
  const double bnorm = norm2(b);
  double rel = nan_value, err_a = nan_value, err_2 = nan_value;
  if (o.x.size() == A.rows() && o.x.allFinite()) {
    Vector res;
    residual(A, o.x, b, res);
    rel = bnorm > 0 ? norm2(res) / bnorm : norm2(res);
    if (ref.x.size()) {
      const Vector e = o.x - ref.x;
      err_a = ref.a_norm > 0 ? a_norm(A, e) / ref.a_norm : nan_value;
      err_2 = ref.l2_norm > 0 ? norm2(e) / ref.l2_norm : nan_value;
    }
  } else if (o.status != "error") {
    o.message += std::string(o.message.empty() ? "" : "; ") + "solution is missing or not finite";
  }
  std::cerr << " " << o.status << " (" << o.st.iterations << " iterations, relative residual " << rel << ")\n";
  r.attrs["status"] = o.status;
  r.attrs["message"] = o.message;
  r.attrs["iterations"] = static_cast<long long>(o.st.iterations);
  r.attrs["final_relative_residual"] = rel;
  r.attrs["reported_relative_residual"] = o.status == "error" ? nan_value : o.st.final_relative_residual;
  r.attrs["setup_time"] = o.setup_time;
  r.attrs["solve_time"] = o.solve_time;
  r.attrs["error_vs_direct"] = err_a;
  r.attrs["error_vs_direct_l2"] = err_2;
  // Solver statistics; a key that collides with the harness's own gets a "solver_" prefix.
  for (const auto& [k, v] : o.stats) r.attrs[r.attrs.count(k) ? "solver_" + k : k] = v;
  r.datasets["residual"] = o.st.residual_history;
  r.datasets["time"] = o.st.residual_time;
  if (o.x.size() == A.rows()) r.datasets["solution"] = std::vector<double>(o.x.data(), o.x.data() + o.x.size());
  for (const auto& [k, v] : o.arrays) r.datasets[r.datasets.count(k) ? "solver_" + k : k] = v;
}

}  // namespace

int cmd_solve(const CommandArgs& argv) {
  Args args("solve", argv, {{"--system"}, {"--solver"}, {"--tol"}, {"--set", true, true}, {"--out"}, {"--form"}, {"--quiet", false}, {"--append", false}});
  // Everything is checked before anything is written.
  const std::string system_path = args.require("--system");
  const std::string out = args.require("--out");
  const auto runs = method_runs(parse_methods(args.require("--solver"), true), args.get("--form", ""));
  check_output("solve", "--out", out, {system_path});
  ResultsWriter writer = command_writer("solve", out, args.has("--append"));  // replaces out unless --append
  const CapturedSystem sys = read_system_h5(system_path);
  Params p = params_from_system(sys, system_path);
  for (const auto& s : args.all("--set")) apply_set(p, s);
  if (args.has("--tol")) set_param(p, "linear.tol", args.get("--tol"), "solve --tol");
  validate(p);
  if (p.threads > 0) omp_set_num_threads(p.threads);
  const std::string prefix = strip_h5(system_path);
  const std::string stem = fs::path(prefix).filename().string();
  // Each run's parameters and form, resolved (and refused where impossible) before anything is written.
  std::vector<std::pair<Params, std::string>> setups;
  for (const auto& run : runs) {
    Params q = p;
    if (!run.form.empty()) q.form = run.form;
    if (q.form == "primal" && !sys.has_primal())
      throw Error("solve: " + system_path + " has no primal data (/J; captured before the primal form existed): recapture it, or use form=dual");
    setups.emplace_back(q, sys.has_primal() ? resolve_form(q.form, sys.alpha_tilde) : "dual");
  }
  const bool show = progress_wanted(args);
  DirectReference ref;
  {
    ProgressLine line(show, "solve: direct reference (cholmod) ...");
    ref = direct_reference(sys.A, sys.b, p);
    line.erase();
  }

  std::vector<RunRecord> added;  // reported at the end (the file may hold many more)
  for (size_t i = 0; i < runs.size(); ++i) {
    const auto& [q, form] = setups[i];
    RunRecord r;
    r.name = stem + "_" + runs[i].tag;
    add_provenance(r, q);
    // The capture's identity (the parameters above are those of the solve).
    for (const char* k : {"frame", "substep", "iteration", "capture_solver", "asymmetry"})
      if (sys.attrs.count(k)) r.attrs[k] = sys.attrs.at(k);
    r.attrs["scene"] = attr_text(sys.attrs, "scene");
    r.attrs["level"] = std::string("linear");
    r.attrs["system"] = prefix;
    r.attrs["solver"] = runs[i].method;
    r.attrs["form_used"] = form;
    r.attrs["rows"] = static_cast<long long>(sys.A.rows());
    r.attrs["nnz"] = static_cast<long long>(sys.A.nonZeros());
    r.attrs["rhs_norm"] = norm2(sys.b);
    r.attrs["direct_status"] = ref.status;
    r.attrs["direct_relative_residual"] = ref.relative_residual;
    const std::string head = "solve: " + stem + " with " + runs[i].tag + " ...";
    std::cerr << head << std::flush;
    SolveOutcome outcome;
    {
      ProgressLine line(show, head);  // a solve reports nothing on its way: run i/N and the time
      line.set("run " + std::to_string(i + 1) + "/" + std::to_string(runs.size()), -1);
      outcome = solve_one(sys, runs[i].method, q, form);
    }
    record_outcome(r, std::move(outcome), ref, sys.A, sys.b);
    r.name = append_command_run("solve", writer, r, writer.runs_in_file());
    added.push_back(std::move(r));
  }
  close_command_writer("solve", writer);
  print_runs(added, "table");
  return 0;
}

}  // namespace xb
