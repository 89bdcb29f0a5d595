// sweep SPEC.toml --out FILE.h5: every (grid point × solver × repeat) of a spec is one run,
// appended to FILE as soon as it ends (atomically, harness/io/recorder.hpp). Rerunning the same
// command skips the runs already in FILE (matched by their sweep_key) and does the rest; a failed
// run is recorded with its status and the sweep goes on. The jobs run one at a time, or spread
// over processes (--jobs N), mpirun's ranks or a job array's tasks (--part K/N): sweep_jobs.hpp.
#include "args.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "run_setup.hpp"
#include "../sim/simulation.hpp"
#include "../io/file_lock.hpp"
#include "../io/run_record.hpp"
#include "sweep.hpp"
#include "sweep_jobs.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/mpi/partition.hpp"
#include "../../solvers/timer.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <unistd.h>

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
  existing = static_cast<int>(runs.size() + bad.size());
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
  RunRecord run(const SweepJob& job, RunResult& res, std::function<void(const IterationProgress&)> on_iteration) {
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
    RunRecord rec = make_simulation_record(job.params.scene + "_" + job.solver, job.params, job.solver, res);
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

// A sweep as a process runs it: the spec and its jobs, checked, and where the runs go.
struct Sweep {
  SweepSpec spec;
  std::vector<SweepJob> jobs;
  std::string base, swept, out;
  bool show = false;
};

// Everything checked before anything runs: the spec, every combination, the output.
Sweep prepare(const Args& args) {
  if (args.positional().empty())
    throw Error("sweep: which spec? (sweep SPEC.toml --out FILE.h5 [--size NAME] [--profile NAME|FILE] [--time-budget S] [--jobs N] [--part K/N])");
  Sweep s;
  s.out = args.require("--out");
  s.spec = parse_sweep_spec(args.positional()[0], args.get("--size", "default"), args.get("--profile", ""));
  if (args.has("--time-budget")) s.spec.time_budget = time_budget_flag(args, "sweep");
  s.jobs = expand_sweep(s.spec);
  s.base = sweep_base_hash(s.spec);
  for (const auto& [k, v] : s.spec.grid) s.swept += (s.swept.empty() ? "" : ",") + k;
  // Inputs are never outputs: the spec, the scene and every mesh of the grid; a file that exists
  // must be a results file (a sweep appends to it).
  std::vector<std::string> inputs = {args.positional()[0], s.spec.scene};
  for (const auto& j : s.jobs)
    for (const auto& m : mesh_inputs(j.params))
      if (std::find(inputs.begin(), inputs.end(), m) == inputs.end()) inputs.push_back(m);
  check_output("sweep", "--out", s.out, inputs);
  if (std::filesystem::exists(s.out) && !is_results_file(s.out))
    throw Error("sweep: --out " + s.out + " exists and is not an xpbd-bench results file; a sweep only appends to one");
  s.show = progress_wanted(args);
  return s;
}

// Runs the jobs next() gives (numbers into s.jobs, one by one; -1 at the end) and appends each
// run to s.out as it ends. `tag` ("" for a sweep run by one process, else which process) goes
// in each line, written whole after the run when processes share stderr.
void run_jobs(const Sweep& s, const std::function<int()>& next, int total, int done, const std::string& tag, int kept) {
  JobRunner runner(s.spec, s.base, s.swept);
  ResultsWriter writer(s.out, false);
  const bool alone = tag.empty();
  int timed = 0;
  double spent = 0;
  for (int i = next(); i >= 0; i = next()) {
    const SweepJob& job = s.jobs.at(static_cast<size_t>(i));
    const int shown = alone ? done + 1 : job.index + 1;
    const std::string head = "sweep" + tag + ": [" + std::to_string(shown) + "/" + std::to_string(total) + "] " +
                             describe(job, s.spec.repeats) + " ...";
    if (alone) std::cerr << head << std::flush;
    Timer clock;
    RunResult res;
    RunRecord rec;
    {
      ProgressLine line(s.show && alone, head);
      if (timed > 0) line.set_remaining(spent / timed * (total - done));  // the sweep's ETA: runs left × mean
      rec = runner.run(job, res, [&line](const IterationProgress& p) { line.set_iteration(p); });
    }
    std::ostringstream os;
    os << (alone ? "" : head) << " " << res.status << " (" << res.outer_iterations << " outer iterations, rel. dual residual "
       << std::setprecision(3) << res.relative_dual_residual << ", " << std::setprecision(3) << res.wall_time << " s)\n";
    std::cerr << os.str() << std::flush;  // before the write, so that a failed one is a line of its own
    const int held = writer.jobs_held_already();
    const std::string name = append_command_run("sweep", writer, rec, std::max(kept, writer.runs_in_file()),
                                                ": run the same sweep again to resume from there");
    if (writer.jobs_held_already() > held)  // another sweep finished this job first: one run per job
      std::cerr << "sweep" << tag << ": " << describe(job, s.spec.repeats) << ": " << s.out << " holds this job already (run "
                << name << ", by another writer meanwhile): this run is not kept\n";
    ++done;
    spent += clock.seconds();
    ++timed;
  }
  close_command_writer("sweep", writer);
}

// argv without --jobs N: what each of --jobs' processes runs.
std::vector<std::string> without_jobs(const CommandArgs& argv) {
  std::vector<std::string> out{"sweep"};
  for (size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] == "--jobs") {
      ++i;
      continue;
    }
    out.push_back(argv[i]);
  }
  return out;
}

// What is left to do: the jobs of this process's part (--part; all without) not yet in the file,
// with the counts of the first line.
struct Todo {
  std::vector<int> jobs;
  int in_part = 0, existing = 0, skipped = 0;
};
Todo left_to_do(const Sweep& s, const SweepPart& part) {
  Todo t;
  const auto finished = finished_runs(s.out, s.base, t.existing, t.skipped);  // resume: what is already in the file
  for (const auto& j : s.jobs) {
    const bool mine = part.has(j.index), done = finished.count(j.key) > 0;
    t.in_part += mine;
    if (mine && !done) t.jobs.push_back(j.index);
  }
  return t;
}

// "sweep: SPEC: 16 runs (3 already in FILE, 13 to do), shared by 2 ranks": with --part, the part's.
void say_start(const Sweep& s, const Args& args, const Todo& t, bool share, int processes) {
  const int total = static_cast<int>(s.jobs.size()), left = static_cast<int>(t.jobs.size());
  std::cerr << "sweep: " << s.spec.path << ": " << total << " runs";
  if (args.has("--part")) std::cerr << "; part " << args.get("--part") << " of them: " << t.in_part;
  std::cerr << " (" << t.in_part - left << " already in " << s.out << ", " << left << " to do)";
  if (share) std::cerr << ", shared by " << mpi_size() << " ranks";
  else if (mpi_size() > 1) std::cerr << ", one at a time: the other ranks serve the distributed solvers (hypre, muelu)";
  else if (processes > 1 && left > 1) std::cerr << " on " << std::min(processes, left) << " processes";
  std::cerr << "\n";
}

// Under mpirun: rank 0's list of jobs to every rank, and the name of the counter (a file in the
// runs folder, file_lock.hpp) by which they take them one by one, so that a slow job holds up no
// other rank.
std::string share_todo(std::vector<int>& jobs, const std::string& out) {
  int n = static_cast<int>(jobs.size());
  MPI_Bcast(&n, 1, MPI_INT, 0, MPI_COMM_WORLD);
  jobs.resize(static_cast<size_t>(n));
  MPI_Bcast(jobs.data(), n, MPI_INT, 0, MPI_COMM_WORLD);
  char id[9] = {};
  if (mpi_rank() == 0) std::snprintf(id, sizeof id, "%s", random_hex8().c_str());
  MPI_Bcast(id, sizeof id, MPI_CHAR, 0, MPI_COMM_WORLD);
  return runs_folder(out) + "/queue-" + id;
}

// The sweep's jobs left to do: by this process, by --jobs' processes or shared by mpirun's ranks.
// Prints the first line; returns the exit code.
int run_sweep(const Sweep& s, const Args& args, const CommandArgs& argv, bool share) {
  const bool rank0 = mpi_rank() == 0;
  const int processes = args.has("--jobs") ? args.get_int("--jobs", 1) : 1;
  if (processes < 1 || processes > 1024) throw Error("sweep: --jobs must be between 1 and 1024");
  const SweepPart part = args.has("--part") ? parse_part(args.get("--part")) : SweepPart{};
  Todo t;
  std::exception_ptr failed;
  if (rank0) {  // rank 0 reads the file for all ranks
    try {
      t = left_to_do(s, part);
    } catch (...) {
      failed = std::current_exception();
    }
  }
  if (share && !all_ranks(!failed) && !failed) return 2;  // rank 0 says why
  if (failed) std::rethrow_exception(failed);
  if (rank0) say_start(s, args, t, share, processes);
  const std::string queue = share ? share_todo(t.jobs, s.out) : "";
  const int left = static_cast<int>(t.jobs.size());
  int rc = 0;
  try {
    if (share) {
      SharedCounter counter(queue);
      const auto next = [&] {
        const long n = counter.next();
        return n < left ? t.jobs[static_cast<size_t>(n)] : -1;
      };
      run_jobs(s, next, static_cast<int>(s.jobs.size()), 0, " (rank " + std::to_string(mpi_rank()) + ")", t.existing);
    } else if (processes > 1 && left > 1) {
      rc = run_queue_workers(std::min(processes, left), t.jobs, without_jobs(argv));
    } else {
      size_t at = 0;
      run_jobs(s, [&] { return at < t.jobs.size() ? t.jobs[at++] : -1; }, t.in_part, t.in_part - left, "", t.existing);
    }
  } catch (...) {
    failed = std::current_exception();
  }
  if (share) {
    MPI_Barrier(MPI_COMM_WORLD);  // every rank's runs are in the file before the summary
    if (rank0) remove_unused_counter(queue);
  }
  if (failed) std::rethrow_exception(failed);
  if (!rank0) return rc;
  print_summary(s.spec, s.jobs, s.out);
  // The sweep did what it was asked (its runs are in the file), so it succeeds: exit code 1 here
  // would be a failed command that changed its output file.
  if (t.skipped)
    std::cerr << "sweep: warning: " << s.out << " holds " << t.skipped
              << " unreadable run(s), named above, left as they are (their jobs ran again)\n";
  return rc;
}
}  // namespace

int cmd_sweep(const CommandArgs& argv) {
  Args args("sweep", argv, {{"--out"}, {"--time-budget"}, {"--size"}, {"--profile"}, {"--quiet", false}, {"--jobs"}, {"--part"}}, 1);
  const bool mpi = mpi_size() > 1, rank0 = mpi_rank() == 0;
  Sweep s;
  bool share = false;
  std::exception_ptr failed;
  try {
    s = prepare(args);
    if (mpi && (args.has("--jobs") || args.has("--part")))
      throw Error("sweep: under mpirun the ranks share the jobs; --jobs and --part are for runs without it");
    share = ranks_share_jobs(s.spec.solvers, s.spec.path);
  } catch (...) {
    failed = std::current_exception();
  }
  if (!all_ranks(!failed)) {  // the same spec fails alike on every rank: rank 0 says why
    if (failed && rank0) std::rethrow_exception(failed);
    return 2;
  }
  if (is_queue_worker()) {  // one of --jobs' processes: the parent checked and counted
    run_jobs(s, next_queued_job, static_cast<int>(s.jobs.size()), 0, " (pid " + std::to_string(::getpid()) + ")", 0);
    return 0;
  }
  if (mpi && !share && !rank0) return 0;  // this rank serves rank 0's distributed solves (main)
  return run_sweep(s, args, argv, share);
}

}  // namespace xb
