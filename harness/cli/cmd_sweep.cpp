// sweep SPEC.toml --out FILE.h5: every (grid point × solver × repeat) of a spec is one run,
// appended to FILE as soon as it ends (atomically, harness/recorder). Rerunning the same command
// skips the runs already in FILE (matched by their sweep_key) and does the rest; a failed run is
// recorded with its status and the sweep goes on.
#include "args.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "run_setup.hpp"
#include "../sim/simulation.hpp"
#include "../io/run_record.hpp"
#include "sweep.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/timer.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

namespace xb {

namespace {

std::string describe(const SweepJob& j, int repeats) {
  std::string s = (j.point_text == "-" ? "" : j.point_text + " ") + j.solver;
  if (repeats > 1) s += " #" + std::to_string(j.repeat);
  return s;
}

void print_table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width;
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size(); ++c) {
      if (width.size() <= c) width.push_back(0);
      width[c] = std::max(width[c], row[c].size());
    }
  for (const auto& row : rows) {
    for (size_t c = 0; c < row.size(); ++c) std::cout << std::left << std::setw(width[c] + 2) << row[c];
    std::cout << "\n";
  }
}

// The runs of this sweep already in `out` (sweep_key → run name) and how many runs it holds.
// Throws if the file holds another sweep's runs.
// Runs that cannot be read are named on stderr and counted in `skipped` (their jobs run again).
std::map<std::string, std::string> finished_runs(const std::string& out, const std::string& base, int& existing,
                                                 int& skipped) {
  std::map<std::string, std::string> finished;
  existing = skipped = 0;
  if (!std::filesystem::exists(out)) return finished;
  std::vector<std::string> bad;
  const auto runs = read_runs(out, false, &bad);
  warn_skipped("sweep", bad);
  skipped = static_cast<int>(bad.size());
  existing = static_cast<int>(runs.size() + bad.size());  // new run names follow every run in the file
  for (const auto& r : runs) {
    const std::string b = attr_cell(r, "sweep_base");
    if (b == "-") continue;
    if (b != base)
      throw Error("sweep: " + out + " holds runs of another sweep (different scene or fixed parameters, run " + r.name +
                  "); write to another --out");
    finished[attr_cell(r, "sweep_key")] = r.name;
  }
  return finished;
}

// One job: the problem of its grid point (built once per point, shared by its solvers and
// repeats; run_simulation copies it), the run, its record with the sweep's attributes.
class JobRunner {
 public:
  JobRunner(const SweepSpec& spec, std::string base, std::string swept)
      : spec_(spec), base_(std::move(base)), swept_(std::move(swept)) {
    opt_.time_budget = spec.time_budget;
    opt_.reference = spec.reference;
  }
  RunRecord run(const SweepJob& job, int index, RunResult& res, std::function<void(const IterationProgress&)> on_iteration) {
    opt_.on_iteration = std::move(on_iteration);
    if (job.point != point_) {
      prob_.reset();
      error_.clear();
      point_ = job.point;
      try {
        prob_ = std::make_unique<Problem>(build_problem(job.params));
      } catch (const std::exception& e) {
        error_ = e.what();
      }
    }
    if (prob_) {
      try {
        res = run_simulation(*prob_, job.params, job.solver, opt_);
      } catch (const std::exception& e) {
        res.status = "error";
        res.message = e.what();
      }
    } else {
      res.status = "error";
      res.message = "cannot build the scene: " + error_;
    }
    RunRecord rec = make_simulation_record(run_name(index, job.params.scene, job.solver), job.params, job.solver, res);
    rec.attrs["sweep_key"] = job.key;
    rec.attrs["sweep_base"] = base_;
    rec.attrs["sweep_params"] = swept_;
    rec.attrs["sweep_point"] = job.point_text;
    rec.attrs["sweep_index"] = static_cast<long long>(job.index);
    rec.attrs["sweep_repeat"] = static_cast<long long>(job.repeat);
    rec.attrs["sweep_spec"] = spec_.path;
    if (!spec_.description.empty()) rec.attrs["sweep_description"] = spec_.description;
    rec.attrs["time_budget"] = spec_.time_budget;
    rec.attrs["reference"] = static_cast<long long>(spec_.reference);
    return rec;
  }

 private:
  const SweepSpec& spec_;
  std::string base_, swept_;
  RunOptions opt_;
  std::unique_ptr<Problem> prob_;
  int point_ = -1;
  std::string error_;
};

// The summary: every run of this sweep, in sweep order, whether run now or before.
void print_summary(const SweepSpec& spec, const std::vector<SweepJob>& jobs, const std::string& out) {
  std::map<std::string, RunRecord> by_key;
  std::vector<std::string> bad;  // named once already, by finished_runs
  if (std::filesystem::exists(out))
    for (auto& r : read_runs(out, false, &bad)) by_key[attr_cell(r, "sweep_key")] = std::move(r);
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> header{"run"};
  for (const auto& [k, v] : spec.grid) header.push_back(k);
  for (const char* c : {"solver", "repeat", "status", "outer_iterations", "final_dual_residual", "relative_dual_residual", "wall_time"})
    header.push_back(c);
  if (spec.reference) header.push_back("final_position_error");
  rows.push_back(header);
  for (const auto& j : jobs) {
    auto it = by_key.find(j.key);
    if (it == by_key.end()) continue;
    const RunRecord& r = it->second;
    std::vector<std::string> row{r.name};
    for (const auto& [k, v] : j.values) row.push_back(v);
    row.push_back(j.solver);
    row.push_back(std::to_string(j.repeat));
    for (const char* c : {"status", "outer_iterations", "final_dual_residual", "relative_dual_residual", "wall_time"})
      row.push_back(attr_cell(r, c));
    if (spec.reference) row.push_back(attr_cell(r, "final_position_error"));
    rows.push_back(row);
  }
  print_table(rows);
}

}  // namespace

int cmd_sweep(const CommandArgs& argv) {
  Args args("sweep", argv, {{"--out"}, {"--time-budget"}, {"--size"}, {"--profile"}, {"--quiet", false}}, 1);
  if (args.positional().empty())
    throw Error("sweep: which spec? (sweep SPEC.toml --out FILE.h5 [--size NAME] [--profile NAME|FILE] [--time-budget S])");
  const std::string out = args.require("--out");
  // The whole spec and every combination are checked before anything runs.
  SweepSpec spec = parse_sweep_spec(args.positional()[0], args.get("--size", "default"), args.get("--profile", ""));
  if (args.has("--time-budget")) spec.time_budget = time_budget_flag(args, "sweep");
  const std::vector<SweepJob> jobs = expand_sweep(spec);
  const std::string base = sweep_base_hash(spec);
  std::string swept;
  for (const auto& [k, v] : spec.grid) swept += (swept.empty() ? "" : ",") + k;
  // Inputs are never outputs: the spec, the scene and every mesh of the grid; a file that exists
  // must be a results file (a sweep appends to it).
  std::vector<std::string> inputs = {args.positional()[0], spec.scene};
  for (const auto& j : jobs)
    for (const auto& m : mesh_inputs(j.params))
      if (std::find(inputs.begin(), inputs.end(), m) == inputs.end()) inputs.push_back(m);
  check_output("sweep", "--out", out, inputs);
  if (std::filesystem::exists(out) && !is_results_file(out))
    throw Error("sweep: --out " + out + " exists and is not an xpbd-bench results file; a sweep only appends to one");
  int existing = 0, skipped = 0;
  auto finished = finished_runs(out, base, existing, skipped);  // resume: what is already in the file
  int todo = 0;
  for (const auto& j : jobs) todo += finished.count(j.key) ? 0 : 1;

  const bool show = progress_wanted(args);
  const int total = static_cast<int>(jobs.size());
  std::cerr << "sweep: " << spec.path << ": " << total << " runs (" << (total - todo) << " already in " << out << ", "
            << todo << " to do)\n";
  JobRunner runner(spec, base, swept);
  int done = total - todo, index = existing, timed = 0;
  double spent = 0;
  for (const auto& job : jobs) {
    if (finished.count(job.key)) continue;
    const std::string head = "sweep: [" + std::to_string(done + 1) + "/" + std::to_string(total) + "] " +
                             describe(job, spec.repeats) + " ...";
    std::cerr << head << std::flush;
    Timer clock;
    RunResult res;
    RunRecord rec;
    {
      ProgressLine line(show, head);
      if (timed > 0) line.set_remaining(spent / timed * (total - done));  // the sweep's ETA: runs left × mean
      rec = runner.run(job, ++index, res, [&line](const IterationProgress& s) { line.set_iteration(s); });
    }
    std::ostringstream os;
    os << " " << res.status << " (" << res.outer_iterations << " outer iterations, rel. dual residual "
       << std::setprecision(3) << res.relative_dual_residual << ", " << std::setprecision(3) << res.wall_time << " s)";
    std::cerr << os.str() << "\n";  // before the write, so that a failed one is a line of its own
    append_command_run("sweep", out, rec, existing == 0 && index == 1, index - 1,
                       ": run the same sweep again to resume from there");
    finished[job.key] = rec.name;
    ++done;
    spent += clock.seconds();
    ++timed;
  }
  print_summary(spec, jobs, out);
  // The sweep did what it was asked (its runs are in the file), so it succeeds: exit code 1 here
  // would be a failed command that changed its output file.
  if (skipped)
    std::cerr << "sweep: warning: " << out << " holds " << skipped
              << " unreadable run(s), named above, left as they are (their jobs ran again)\n";
  return 0;
}

}  // namespace xb
