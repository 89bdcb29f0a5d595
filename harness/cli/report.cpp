#include "report.hpp"

#include "../io/recorder.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace xb {

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
  return it == r.attrs.end() ? "-" : attr_value_text(it->second, 3);
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

void print_repair(const std::string& path, const RepairReport& rep) {
  if (rep.packed) {
    std::cout << "repair: " << path << " holds its " << rep.runs << " runs inline (a packed file): nothing to repair\n";
    return;
  }
  std::cout << "repair: " << path << ": " << rep.runs << " runs; index rebuilt from its run files\n";
  const auto list = [](const char* what, const std::vector<std::string>& items) {
    if (items.empty()) return;
    std::cout << "repair: " << what << " (" << items.size() << "):\n";
    for (size_t i = 0; i < items.size() && i < 20; ++i) std::cout << "  " << items[i] << "\n";
    if (items.size() > 20) std::cout << "  ... and " << items.size() - 20 << " more\n";
  };
  list("runs now in the index that it did not list", rep.found.relinked);
  list("runs it listed that are gone or unreadable, left out", rep.found.dangling);
  list("removed", rep.found.removed);
  for (const auto& n : rep.found.notes) std::cout << "repair: " << n << "\n";
}

void warn_skipped(const std::string& command, const std::vector<std::string>& skipped) {
  for (const auto& s : skipped) std::cerr << command << ": skipped unreadable run: " << s << "\n";
}

namespace {
void print_json(const std::vector<RunRecord>& runs) {
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
}
}  // namespace

namespace {
using Column = std::pair<std::string, std::function<std::string(const RunRecord&)>>;

Column attr_column(const std::string& key) {
  return {key, [key](const RunRecord& r) { return attr_cell(r, key); }};
}

// The measure a run's stop test read (attribute convergence_measure, results/README.md): under
// step = newton ‖∇E‖, whose dual residual is rounding over rounding (λ = −α̃⁻¹C), else the dual
// residual. Files from before the attribute: the dual residual, or under step = newton the relative
// Newton residual (relative ‖∇E‖ up to that rounding), marked with "~".
const char* measure_name(const std::string& m) {
  return m == "energy_gradient" ? "|grad E|" : m == "authors_dual_residual" ? "authors dual" : "dual";
}
bool old_newton(const RunRecord& r) { return !r.attrs.count("convergence_measure") && attr_cell(r, "step") == "newton"; }
std::string measure_cell(const RunRecord& r) {
  if (old_newton(r)) return "~|grad E|";
  const auto it = r.attrs.find("convergence_measure");
  return measure_name(it == r.attrs.end() ? "" : attr_value_text(it->second, 3));
}
std::string final_cell(const RunRecord& r) {
  if (r.attrs.count("convergence_measure")) return attr_cell(r, "final_convergence");
  return old_newton(r) ? "-" : attr_cell(r, "final_dual_residual");
}
std::string relative_cell(const RunRecord& r) {
  if (r.attrs.count("convergence_measure")) return attr_cell(r, "final_relative_convergence");
  return attr_cell(r, old_newton(r) ? "final_relative_newton_residual" : "relative_dual_residual");
}
// Whether the run's reference (--reference) converged in every substep; "-" without one.
std::string reference_cell(const RunRecord& r) {
  if (!r.attrs.count("reference_substeps_unconverged")) return "-";
  const std::string n = attr_cell(r, "reference_substeps_unconverged");
  return n == "0" ? "converged" : n + " of " + attr_cell(r, "substeps_total") + " substeps unconverged";
}

// The reference's certificate (harness/sim/certificate.hpp): the finest position-error threshold
// every substep's reference supports (100 times its error estimate), or how many are uncertified.
std::string certificate_cell(const RunRecord& r) {
  if (!r.attrs.count("reference_substeps_uncertified")) return "-";
  const std::string n = attr_cell(r, "reference_substeps_uncertified");
  if (n != "0") return "uncertified in " + n + " of " + attr_cell(r, "substeps_total") + " substeps";
  return "error <= " + attr_cell(r, "reference_error_estimate") + ", trusted to " +
         attr_cell(r, "reference_certified_threshold");
}

// The simulation table's columns: each run's own convergence measure, and with a reference the
// position error, whether the reference converged and its certificate.
std::vector<Column> simulation_columns(const std::vector<RunRecord>& runs) {
  std::vector<Column> cols;
  for (const char* k : {"scene", "solver", "form_used", "status", "outer_iterations"}) cols.push_back(attr_column(k));
  cols.insert(cols.end(), {{"measure", measure_cell}, {"final", final_cell}, {"relative", relative_cell}});
  const bool reference = std::any_of(runs.begin(), runs.end(), [](const RunRecord& r) {
    return attr_cell(r, "level") == "simulation" && r.attrs.count("reference_substeps_unconverged");
  });
  if (reference)
    cols.insert(cols.end(),
                {attr_column("final_position_error"), {"reference", reference_cell}, {"certificate", certificate_cell}});
  cols.push_back(attr_column("wall_time"));
  return cols;
}

void print_tables(const std::vector<RunRecord>& runs) {
  // One table per level of run, with the columns that matter for it.
  std::vector<Column> linear;
  for (const char* k : {"system", "solver", "form_used", "status", "iterations", "final_relative_residual", "error_vs_direct",
                        "setup_time", "solve_time", "levels", "operator_complexity"})
    linear.push_back(attr_column(k));
  const std::vector<std::pair<std::string, std::vector<Column>>> layouts = {{"simulation", simulation_columns(runs)},
                                                                            {"linear", linear}};
  for (const auto& [level, cols] : layouts) {
    std::vector<std::vector<std::string>> rows;
    std::vector<std::string> warnings;
    for (const auto& r : runs)
      if (attr_cell(r, "level") == level) {
        std::vector<std::string> row{r.name};
        for (const auto& c : cols) row.push_back(c.second(r));
        rows.push_back(row);
        warnings.push_back(timing_warning(r));
      }
    if (rows.empty()) continue;
    std::vector<std::string> header{"run"};
    for (const auto& c : cols) header.push_back(c.first);
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
    if (level == "simulation")
      std::cout << "measure: what each run's stop test read (|grad E| under step = newton, in N; else the dual "
                   "residual); relative: over the same substep's first value; certificate: the worst bound on the "
                   "reference's own position error and the finest position error it can judge (100 times that)\n";
    std::cout << "\n";
  }
}
}  // namespace

void print_runs(const std::vector<RunRecord>& runs, const std::string& format) {
  if (format == "json") print_json(runs);
  else print_tables(runs);
}

int print_report(const std::string& path, const std::string& format) {
  if (format != "table" && format != "json") throw Error("report: unknown format '" + format + "' (valid: table, json)");
  std::vector<std::string> skipped;
  const auto runs = read_runs(path, false, &skipped);
  print_runs(runs, format);
  warn_skipped("report", skipped);
  return static_cast<int>(skipped.size());
}

}  // namespace xb
