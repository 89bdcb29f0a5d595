#include "report.hpp"

#include "../io/recorder.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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
void print_tables(const std::vector<RunRecord>& runs) {
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
}  // namespace

int print_report(const std::string& path, const std::string& format) {
  if (format != "table" && format != "json") throw Error("report: unknown format '" + format + "' (valid: table, json)");
  std::vector<std::string> skipped;
  const auto runs = read_runs(path, false, &skipped);
  if (format == "json") print_json(runs);
  else print_tables(runs);
  warn_skipped("report", skipped);
  return static_cast<int>(skipped.size());
}

}  // namespace xb
