#include "run_record.hpp"

#include "../../solvers/linear_solver.hpp"

#include <dlfcn.h>
#include <omp.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <variant>

#ifndef XB_GIT_SHA
#define XB_GIT_SHA "unknown"
#endif

namespace xb {

namespace {
std::string machine_description() {
  char host[256] = "";
  gethostname(host, sizeof host);
  std::string cpu;
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  return std::string(host) + "; " + cpu + "; " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " cores";
}

std::string now_iso() {
  std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// What the timings of this process ran under, taken once at load time (before main, so before
// any work): the OpenMP wait policy and spin count the runtime read from the environment (libgomp
// reads them at load time too; harness/cli/wait_policy.hpp re-executes with `passive` and a bounded
// spin when no policy was set) and the machine's one-minute load average.
struct ProcessStart {
  std::string omp_wait_policy;  // lower case; "default" when unset or empty (the runtime spins, then sleeps)
  std::string omp_spin_count;   // GOMP_SPINCOUNT as set; "default" when unset (the policy's own)
  double load_average = -1;     // < 0: /proc/loadavg unreadable
  long long cpu_count = 0;
};
ProcessStart read_process_start() {
  ProcessStart s;
  if (const char* w = std::getenv("OMP_WAIT_POLICY")) {
    for (const char* c = w; *c; ++c)
      if (!std::isspace(static_cast<unsigned char>(*c))) s.omp_wait_policy += static_cast<char>(std::tolower(static_cast<unsigned char>(*c)));
  }
  if (s.omp_wait_policy.empty()) s.omp_wait_policy = "default";
  const char* spin = std::getenv("GOMP_SPINCOUNT");
  s.omp_spin_count = spin && *spin ? spin : "default";
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &s.load_average) != 1) s.load_average = -1;
    std::fclose(f);
  }
  s.cpu_count = sysconf(_SC_NPROCESSORS_ONLN);
  return s;
}
const ProcessStart process_start = read_process_start();
}  // namespace

void add_provenance(RunRecord& r, const Params& p) {
  for (const auto& f : param_fields()) {
    const ParamValue v = param_value(p, f);
    if (auto* i = std::get_if<long long>(&v)) r.attrs[f.key] = *i;
    else if (auto* d = std::get_if<double>(&v)) r.attrs[f.key] = *d;
    else r.attrs[f.key] = std::get<std::string>(v);
  }
  r.attrs["git_sha"] = std::string(XB_GIT_SHA);
  r.attrs["machine"] = machine_description();
  r.attrs["omp_threads"] = static_cast<long long>(omp_get_max_threads());
  // OpenBLAS's own threads (harness/cli/wait_policy.hpp); absent with another BLAS.
  if (auto get = reinterpret_cast<int (*)()>(::dlsym(RTLD_DEFAULT, "openblas_get_num_threads")))
    r.attrs["blas_threads"] = static_cast<long long>(get());
  r.attrs["omp_wait_policy"] = process_start.omp_wait_policy;
  r.attrs["omp_spin_count"] = process_start.omp_spin_count;
  if (process_start.load_average >= 0) r.attrs["load_average"] = process_start.load_average;
  r.attrs["cpu_count"] = process_start.cpu_count;
  r.attrs["created"] = now_iso();
}

namespace {
// The per-iteration arrays of the log, by dataset name (results/README.md); global_only: written
// for global methods only (the linear solve's, the step's).
using LogMember = std::variant<std::vector<double> IterationLog::*, std::vector<long long> IterationLog::*,
                               std::vector<std::string> IterationLog::*>;
struct LogArray {
  const char* name;
  LogMember member;
  bool global_only;
};
const LogArray log_arrays[] = {
    {"frame", &IterationLog::frame, false},
    {"substep", &IterationLog::substep, false},
    {"iteration", &IterationLog::iteration, false},
    {"dual_residual", &IterationLog::dual_residual, false},
    {"relative_dual_residual", &IterationLog::relative_dual_residual, false},
    {"authors_dual_residual", &IterationLog::authors_dual_residual, false},
    {"authors_relative_dual_residual", &IterationLog::authors_relative_dual_residual, false},
    {"primal_residual", &IterationLog::primal_residual, false},
    {"newton_residual", &IterationLog::newton_residual, false},
    {"relative_newton_residual", &IterationLog::relative_newton_residual, false},
    {"energy", &IterationLog::energy, false},
    {"wall_time", &IterationLog::wall_time, false},
    {"step_time", &IterationLog::step_time, false},
    {"step_length", &IterationLog::step_length, true},
    {"line_search_trials", &IterationLog::line_search_trials, true},
    {"exact_hessian", &IterationLog::exact_hessian, true},
    {"projected_elements", &IterationLog::projected_elements, true},
    {"fill_time", &IterationLog::fill_time, true},
    {"linear_iterations", &IterationLog::linear_iterations, true},
    {"linear_setup_time", &IterationLog::linear_setup_time, true},
    {"linear_solve_time", &IterationLog::linear_solve_time, true},
    {"linear_relative_residual", &IterationLog::linear_relative_residual, true},
    {"linear_tolerance", &IterationLog::linear_tolerance, true},
    {"linear_setup_action", &IterationLog::linear_setup_action, true},
    {"linear_history/residual", &IterationLog::linear_history_residual, true},
    {"linear_history/time", &IterationLog::linear_history_time, true},
    {"linear_history/offset", &IterationLog::linear_history_offset, true},
};

// The Newton residual's last entry, and where every α̃ > 0 what the reference's ‖∇E‖ reached:
// how far a run got towards the backward-Euler solution (results/README.md).
void add_newton_attributes(RunRecord& r, const IterationLog& L) {
  if (!L.newton_residual.empty()) {
    r.attrs["final_newton_residual"] = L.newton_residual.back();
    r.attrs["final_relative_newton_residual"] = L.relative_newton_residual.back();
  }
  if (!L.reference_relative_energy_gradient.empty()) {
    double worst = 0;
    for (double v : L.reference_relative_energy_gradient) worst = std::max(worst, v);
    r.attrs["reference_energy_gradient"] = worst;
    r.datasets["reference/relative_energy_gradient"] = L.reference_relative_energy_gradient;
  }
}
// The measure the run's stop test read (results/README.md): ‖∇E‖ under step = newton and vbd/avbd (its dual
// residual is rounding over rounding there: λ = −α̃⁻¹C), else the dual residual `residual_metric`
// names; its last value and that over the same substep's first, so `report` shows each run's own.
void add_convergence_attributes(RunRecord& r, const Params& p, bool block_descent, const IterationLog& L) {
  if (L.iteration.empty()) return;
  size_t first = L.iteration.size() - 1;
  while (first > 0 && L.iteration[first] != 0) --first;
  double last = 0, start = 0;
  if (p.step == "newton" || block_descent) {  // g = h²∇E: ‖∇E‖ = ‖g‖/h², in N
    const double h = p.dt / p.substeps;
    r.attrs["convergence_measure"] = std::string("energy_gradient");
    last = L.primal_residual.back() / (h * h);
    start = L.primal_residual[first] / (h * h);
  } else if (p.residual_metric == "authors") {
    r.attrs["convergence_measure"] = std::string("authors_dual_residual");
    last = L.authors_dual_residual.back();
    start = L.authors_dual_residual[first];
  } else {
    r.attrs["convergence_measure"] = std::string("dual_residual");
    last = L.dual_residual.back();
    start = L.dual_residual[first];
  }
  r.attrs["final_convergence"] = last;
  r.attrs["final_relative_convergence"] = start > 0 ? last / start : 0.0;
}
// The reference of every substep (harness/sim/reference.hpp), its certificate and the error against
// it (results/README.md, the reference/ group).
void add_reference_records(RunRecord& r, const RunResult& res) {
  const IterationLog& L = res.log;
  r.attrs["reference_method"] = res.reference_method;
  double worst = 0, estimate = 0, threshold = 0;
  long long unconverged = 0, uncertified = 0;
  for (size_t i = 0; i < L.reference_status.size(); ++i) {
    worst = std::max(worst, L.reference_relative_dual_residual[i]);
    if (!L.reference_success[i]) ++unconverged;
    if (!L.reference_certified[i]) ++uncertified;
    estimate = std::max(estimate, L.reference_error_estimate[i]);  // ∞ wins; NaN never occurs
    threshold = std::max(threshold, L.reference_certified_threshold[i]);
  }
  r.attrs["reference_dual_residual"] = worst;
  r.attrs["reference_substeps_unconverged"] = unconverged;
  r.attrs["reference_substeps_uncertified"] = uncertified;
  r.attrs["reference_error_estimate"] = estimate;
  r.attrs["reference_certified_threshold"] = threshold;
  r.attrs["reference_time"] = res.reference_time;
  r.datasets["position_error"] = L.position_error;
  r.datasets["reference/relative_dual_residual"] = L.reference_relative_dual_residual;
  r.datasets["reference/iterations"] = L.reference_iterations;
  r.datasets["reference/status"] = L.reference_status;
  r.datasets["reference/success"] = L.reference_success;
  r.datasets["reference/time"] = L.reference_time;
  r.datasets["reference/energy_gradient"] = L.reference_energy_gradient;
  r.datasets["reference/gradient_floor"] = L.reference_gradient_floor;
  r.datasets["reference/error_scale"] = L.reference_error_scale;
  r.datasets["reference/error_estimate"] = L.reference_error_estimate;
  r.datasets["reference/contraction"] = L.reference_contraction;
  r.datasets["reference/certified"] = L.reference_certified;
  r.datasets["reference/certified_threshold"] = L.reference_certified_threshold;
  r.datasets["reference/certificate_note"] = L.reference_certificate_note;
  if (!L.reference_source.empty()) r.datasets["reference/source"] = L.reference_source;
  if (!res.reference_file.empty()) r.attrs["reference_file"] = res.reference_file;
  if (!L.position_error.empty()) r.attrs["final_position_error"] = L.position_error.back();
}
}  // namespace

RunRecord make_simulation_record(const std::string& name, const Params& p, const std::string& method,
                                 const RunResult& res) {
  RunRecord r;
  r.name = name;
  add_provenance(r, p);
  r.attrs["level"] = std::string("simulation");
  r.attrs["scene"] = p.scene;
  r.attrs["solver"] = method;
  r.attrs["form_used"] = res.form_used;
  r.attrs["profile"] = p.profile;
  r.attrs["status"] = res.status;
  r.attrs["message"] = res.message;
  r.attrs["outer_iterations"] = res.outer_iterations;
  r.attrs["final_dual_residual"] = res.final_dual_residual;
  add_newton_attributes(r, res.log);
  const MethodInfo* info = find_method(method);
  add_convergence_attributes(r, p, info && info->block_descent, res.log);
  r.attrs["relative_dual_residual"] = res.relative_dual_residual;
  r.attrs["wall_time"] = res.wall_time;
  r.attrs["substeps_total"] = static_cast<long long>(res.substeps_total);
  r.attrs["substeps_converged"] = static_cast<long long>(res.substeps_converged);
  for (const auto& [k, v] : res.stats) r.attrs[k] = v;
  for (const auto& [k, v] : res.arrays) r.datasets[k] = v;
  const IterationLog& L = res.log;
  const MethodInfo* m = find_method(method);
  const bool global = m && !m->local;
  for (const auto& a : log_arrays)
    if (!a.global_only || global) std::visit([&](auto member) { r.datasets[a.name] = L.*member; }, a.member);
  r.datasets["substep_status"] = L.substep_status;
  r.datasets["substep_success"] = L.substep_success;
  if (!L.relative_gradient_floor.empty()) {  // step = newton
    r.datasets["relative_gradient_floor"] = L.relative_gradient_floor;
    r.datasets["active_bounds"] = L.active_bounds;
    r.datasets["hessian_time"] = L.hessian_time;
    r.datasets["inverted_elements"] = L.inverted_elements;
    r.datasets["smallest_twist_sum"] = L.smallest_twist_sum;
  }
  if (!L.trust_region_radius.empty()) {  // xpbd.globalization = trust_region
    r.datasets["trust_region_radius"] = L.trust_region_radius;
    r.datasets["trust_region_ratio"] = L.trust_region_ratio;
    r.datasets["trust_region_shift"] = L.trust_region_shift;
    r.datasets["trust_region_curvature"] = L.trust_region_curvature;
    r.datasets["trust_region_boundary"] = L.trust_region_boundary;
    r.datasets["trust_region_negative_curvature"] = L.trust_region_negative_curvature;
    r.datasets["trust_region_rejections"] = L.trust_region_rejections;
  }
  if (!L.reference_status.empty()) add_reference_records(r, res);
  std::vector<double> pos(res.final_positions.data(), res.final_positions.data() + res.final_positions.size());
  r.datasets["final_positions"] = pos;
  return r;
}

std::string run_name(int index, const std::string& scene, const std::string& solver) {
  std::ostringstream os;
  os << std::setw(4) << std::setfill('0') << index << "_" << scene << "_" << solver;
  return os.str();
}

}  // namespace xb
