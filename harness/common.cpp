#include "common.hpp"

#include "../problems/error.hpp"
#include "profile.hpp"
#include "reference.hpp"
#include "../problems/scene.hpp"
#include "../solvers/distributed.hpp"
#include "../solvers/linear_solver.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#ifndef XB_GIT_SHA
#define XB_GIT_SHA "unknown"
#endif

namespace xb {

Params resolve_params(const std::string& scene, const std::vector<std::string>& sets, const std::string& profile) {
  Params p;
  load_scene_file(resolve_scene(scene), p);
  if (!profile.empty()) apply_profile(profile, p);
  for (const auto& kv : sets) apply_set(p, kv);
  validate(p);
  return p;
}

void apply_set(Params& p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) throw Error("--set '" + kv + "': expected key=value");
  set_param(p, kv.substr(0, eq), kv.substr(eq + 1), "--set");
}

std::vector<std::string> parse_methods(const std::string& list, bool linear_only) {
  std::vector<std::string> names;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) names.push_back(item);
  if (names.empty()) throw Error("no solver given (--solver A,B,...)");
  for (const auto& n : names) {
    const MethodInfo* m = find_method(n);
    if (!m || (linear_only && m->local)) {
      std::string valid;
      for (const auto& x : methods())
        if (!(linear_only && x.local)) valid += (valid.empty() ? "" : ", ") + x.name;
      throw Error("unknown solver '" + n + "' (valid: " + valid + ")");
    }
    if (!m->available) throw Error("solver '" + n + "' is not available: " + m->reason);
    if (mpi_size() > 1 && !method_is_distributed(n))
      throw Error("solver '" + n + "' cannot run distributed (this is an MPI run with " + std::to_string(mpi_size()) +
                  " processes; only hypre and muelu can): run it without mpirun");
  }
  return names;
}

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
// any work): the OpenMP wait policy the runtime read from the environment (libgomp reads it at
// load time too; harness/main.cpp re-executes with `passive` when none was set) and the machine's
// one-minute load average.
struct ProcessStart {
  std::string omp_wait_policy;  // lower case; "default" when unset or empty (the runtime spins, then sleeps)
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
  r.attrs["omp_wait_policy"] = process_start.omp_wait_policy;
  if (process_start.load_average >= 0) r.attrs["load_average"] = process_start.load_average;
  r.attrs["cpu_count"] = process_start.cpu_count;
  r.attrs["created"] = now_iso();
}

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
  r.attrs["relative_dual_residual"] = res.relative_dual_residual;
  r.attrs["wall_time"] = res.wall_time;
  r.attrs["substeps_total"] = static_cast<long long>(res.substeps_total);
  r.attrs["substeps_converged"] = static_cast<long long>(res.substeps_converged);
  for (const auto& [k, v] : res.stats) r.attrs[k] = v;
  for (const auto& [k, v] : res.arrays) r.datasets[k] = v;
  const IterationLog& L = res.log;
  r.datasets["frame"] = L.frame;
  r.datasets["substep"] = L.substep;
  r.datasets["iteration"] = L.iteration;
  r.datasets["dual_residual"] = L.dual_residual;
  r.datasets["relative_dual_residual"] = L.relative_dual_residual;
  r.datasets["authors_dual_residual"] = L.authors_dual_residual;
  r.datasets["authors_relative_dual_residual"] = L.authors_relative_dual_residual;
  r.datasets["primal_residual"] = L.primal_residual;
  r.datasets["energy"] = L.energy;
  r.datasets["wall_time"] = L.wall_time;
  r.datasets["step_time"] = L.step_time;
  const MethodInfo* m = find_method(method);
  if (m && !m->local) {
    r.datasets["step_length"] = L.step_length;
    r.datasets["linear_iterations"] = L.linear_iterations;
    r.datasets["linear_setup_time"] = L.linear_setup_time;
    r.datasets["linear_solve_time"] = L.linear_solve_time;
    r.datasets["linear_relative_residual"] = L.linear_relative_residual;
    r.datasets["linear_setup_action"] = L.linear_setup_action;
    r.datasets["linear_history/residual"] = L.linear_history_residual;
    r.datasets["linear_history/time"] = L.linear_history_time;
    r.datasets["linear_history/offset"] = L.linear_history_offset;
  }
  if (!L.reference_status.empty()) {
    // The reference of every substep (harness/reference.hpp) and the error against it.
    r.attrs["reference_method"] = reference_method_description();
    double worst = 0;
    long long unconverged = 0;
    for (size_t i = 0; i < L.reference_status.size(); ++i) {
      worst = std::max(worst, L.reference_relative_dual_residual[i]);
      if (L.reference_status[i] != "converged") ++unconverged;
    }
    r.attrs["reference_dual_residual"] = worst;
    r.attrs["reference_substeps_unconverged"] = unconverged;
    r.attrs["reference_time"] = res.reference_time;
    r.datasets["position_error"] = L.position_error;
    r.datasets["reference/relative_dual_residual"] = L.reference_relative_dual_residual;
    r.datasets["reference/iterations"] = L.reference_iterations;
    r.datasets["reference/status"] = L.reference_status;
    if (!L.position_error.empty()) r.attrs["final_position_error"] = L.position_error.back();
  }
  std::vector<double> pos(res.final_positions.data(), res.final_positions.data() + res.final_positions.size());
  r.datasets["final_positions"] = pos;
  return r;
}

std::vector<MethodRun> method_runs(const std::vector<std::string>& methods, const std::string& form_list) {
  std::vector<std::string> forms;
  std::stringstream ss(form_list);
  for (std::string f; std::getline(ss, f, ',');) {
    if (f != "dual" && f != "primal" && f != "auto") throw Error("--form: unknown form '" + f + "' (valid: dual, primal, auto)");
    forms.push_back(f);
  }
  if (forms.empty()) forms.push_back("");
  std::vector<MethodRun> runs;
  for (const auto& m : methods) {
    if (find_method(m)->local) {
      runs.push_back({m, "", m});
      continue;
    }
    for (const auto& f : forms) runs.push_back({m, f, forms.size() > 1 ? m + "_" + f : m});
  }
  return runs;
}

std::string run_name(int index, const std::string& scene, const std::string& solver) {
  std::ostringstream os;
  os << std::setw(4) << std::setfill('0') << index << "_" << scene << "_" << solver;
  return os.str();
}

namespace {
std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\t': o += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04x", c);
          o += b;
        } else {
          o += c;
        }
    }
  }
  return o;
}

std::string json_value(const AttrValue& v) {
  if (auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&v)) {
    if (!std::isfinite(*d)) return "null";
    char b[64];
    std::snprintf(b, sizeof b, "%.17g", *d);
    return b;
  }
  std::string out = "\"";  // built in place: GCC 12 warns (-Wrestrict, falsely) on "\"" + s
  out += json_escape(std::get<std::string>(v));
  out += '"';
  return out;
}

}  // namespace

std::string attr_cell(const RunRecord& r, const std::string& key) {
  auto it = r.attrs.find(key);
  if (it == r.attrs.end()) return "-";
  if (auto* i = std::get_if<long long>(&it->second)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&it->second)) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", *d);
    return b;
  }
  return std::get<std::string>(it->second);
}

namespace {
// A run's timings are suspect when it started on a busy machine: a one-minute load average above
// the CPU count less this allowance means the other work alone kept (nearly) every CPU busy, so
// the run's full-width OpenMP team shared its cores. Half a CPU of headroom, not more: the load
// average cannot tell whose load it is (a run started within a minute of the harness's own
// previous full-width run is flagged too), and a flagged run is a prompt to rerun, not an error.
constexpr double load_allowance = 0.5;

// Why a run's timings may be inflated ("" = nothing known against them). Each criterion needs
// its attributes; runs recorded before they existed are judged on nothing.
std::string timing_warning(const RunRecord& r) {
  auto number = [&](const char* k, double& out) {
    auto it = r.attrs.find(k);
    if (it == r.attrs.end()) return false;
    if (auto* d = std::get_if<double>(&it->second)) out = *d;
    else if (auto* i = std::get_if<long long>(&it->second)) out = static_cast<double>(*i);
    else return false;
    return true;
  };
  std::string why;
  double load = 0, cpus = 0;
  if (number("load_average", load) && number("cpu_count", cpus) && cpus > 0 && load > cpus - load_allowance) {
    char b[64];
    std::snprintf(b, sizeof b, "load %.2f on %.0f CPUs", load, cpus);
    why = b;
  }
  auto it = r.attrs.find("omp_wait_policy");
  if (it != r.attrs.end()) {
    const auto* policy = std::get_if<std::string>(&it->second);
    if (policy && *policy != "passive") why += (why.empty() ? "" : "; ") + ("wait policy " + *policy);
  }
  return why;
}
bool has_timing_provenance(const RunRecord& r) {
  return r.attrs.count("load_average") || r.attrs.count("omp_wait_policy");
}
}  // namespace

void print_report(const std::string& path, const std::string& format) {
  const auto runs = read_runs(path, false);
  if (format == "json") {
    std::cout << "[";
    for (size_t i = 0; i < runs.size(); ++i) {
      std::cout << (i ? ",\n " : "\n ") << "{\"run\": \"" << json_escape(runs[i].name) << "\"";
      for (const auto& [k, v] : runs[i].attrs) std::cout << ", \"" << json_escape(k) << "\": " << json_value(v);
      // Derived, for runs that carry the timing provenance: whether the timings are suspect, and why.
      if (has_timing_provenance(runs[i])) {
        const std::string why = timing_warning(runs[i]);
        std::cout << ", \"timing_suspect\": " << (why.empty() ? "false" : "true");
        if (!why.empty()) std::cout << ", \"timing_note\": \"" << json_escape(why) << "\"";
      }
      std::cout << "}";
    }
    std::cout << "\n]\n";
    return;
  }
  if (format != "table") throw Error("report: unknown format '" + format + "' (valid: table, json)");
  // One table per level of run, with the columns that matter for it.
  const std::vector<std::pair<std::string, std::vector<std::string>>> layouts = {
      {"simulation", {"scene", "solver", "form_used", "status", "outer_iterations", "final_dual_residual", "relative_dual_residual", "wall_time"}},
      {"linear", {"system", "solver", "form_used", "status", "iterations", "final_relative_residual", "error_vs_direct", "setup_time", "solve_time", "levels", "operator_complexity"}},
  };
  for (const auto& [level, cols] : layouts) {
    std::vector<std::vector<std::string>> rows;
    std::vector<std::string> warnings;
    for (const auto& r : runs)
      if (attr_cell(r, "level") == level) {
        std::vector<std::string> row{r.name};
        for (const auto& c : cols) row.push_back(attr_cell(r, c));
        rows.push_back(row);
        warnings.push_back(timing_warning(r));
      }
    if (rows.empty()) continue;
    std::vector<std::string> header{"run"};
    header.insert(header.end(), cols.begin(), cols.end());
    // A `timing` column only when some run of this table was timed under load or spinning.
    const bool flagged = std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) { return !w.empty(); });
    if (flagged) {
      header.push_back("timing");
      for (size_t i = 0; i < rows.size(); ++i) rows[i].push_back(warnings[i].empty() ? "-" : "* " + warnings[i]);
    }
    std::vector<size_t> width(header.size());
    for (size_t c = 0; c < header.size(); ++c) {
      width[c] = header[c].size();
      for (const auto& row : rows) width[c] = std::max(width[c], row[c].size());
    }
    auto line = [&](const std::vector<std::string>& row) {
      for (size_t c = 0; c < row.size(); ++c) std::cout << std::left << std::setw(width[c] + 2) << row[c];
      std::cout << "\n";
    };
    line(header);
    for (const auto& row : rows) line(row);
    if (flagged)
      std::cout << "* timings suspect: started with the 1-min load average above CPUs - " << load_allowance
                << ", or OpenMP threads spinning (wait policy not passive); rerun on a quiet machine\n";
    std::cout << "\n";
  }
}

}  // namespace xb
