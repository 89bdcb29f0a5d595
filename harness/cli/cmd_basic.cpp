// list, run, report and pack.
#include "args.hpp"
#include "commands.hpp"
#include "report.hpp"
#include "outputs.hpp"
#include "profile.hpp"
#include "progress.hpp"
#include "run_setup.hpp"
#include "../sim/simulation.hpp"
#include "../io/run_record.hpp"
#include "../io/mesh_writer.hpp"
#include "../io/schema.hpp"
#include "../io/state_io.hpp"

#include "../../core/error.hpp"
#include "../../problems/scene.hpp"
#include "../../solvers/linear_solver.hpp"

#include <filesystem>
#include <iostream>
#include <optional>

namespace xb {

int cmd_list(const CommandArgs& argv) {
  Args args("list", argv, {});
  std::cout << "scenes:\n";
  for (const auto& s : scene_names()) std::cout << "  " << s << "\n";
  std::cout << "solvers:\n";
  for (const auto& m : methods()) {
    std::cout << "  " << m.name << (m.local ? "  [local]" : "  [global]");
    if (!m.available) std::cout << "  unavailable: " << m.reason;
    std::cout << "\n";
  }
  std::cout << "parameters (key = default: doc):\n";
  const Params defaults;
  for (const auto& f : param_fields()) std::cout << "  " << f.key << " = " << param_to_string(defaults, f) << ": " << f.doc << "\n";
  return 0;
}

int cmd_schema(const CommandArgs& argv) {
  Args args("schema", argv, {});
  std::cout << schema_json();
  return 0;
}

namespace {
// The files a run writes as it goes (--write-meshes: DIR/<scene>_<solver>_NNNN.ply per frame;
// --save-state after frame F), from inside the stepper. The stepper turns any exception into a run
// with status error; a failed write (a full disk) is kept in `failed` too, to end the command.
void add_frame_writers(RunOptions& opt, const Args& args, const Problem& prob, const std::string& name,
                       const std::string& save_state, int state_frame, const Params& q, std::optional<WriteError>& failed) {
  auto keeping = [&failed](auto write) {
    return [&failed, write](auto&&... a) {
      try {
        write(a...);
      } catch (const WriteError& e) {
        failed.emplace(e);
        throw;
      }
    };
  };
  if (args.has("--write-meshes"))
    opt.on_frame = keeping([&prob, dir = args.get("--write-meshes"), name](int frame, const Eigen::Matrix3Xd& x) {
      write_ply(frame_ply_path(dir, name, frame), prob, x);
    });
  if (!save_state.empty())
    opt.on_state = keeping([&q, save_state, state_frame](const SimState& s) {
      if (s.frame == state_frame + 1) write_state(save_state, s, q);
    });
}

// --time-budget, --memory-limit (caps the process's data segment now), --reference and
// --reference-file (which implies --reference: per-substep reference and position_error).
RunOptions run_options(const Args& args) {
  RunOptions opt;
  opt.time_budget = time_budget_flag(args, "run");
  opt.memory_limit = memory_limit_flag(args, "run");
  opt.reference = args.has("--reference") || args.has("--reference-file");
  opt.reference_file = args.get("--reference-file", "");
  if (args.has("--reference-file") && opt.reference_file.empty()) throw Error("run: --reference-file needs a path");
  return opt;
}
}  // namespace

int cmd_run(const CommandArgs& argv) {
  Args args("run", argv,
            {{"--scene"}, {"--solver"}, {"--frames"}, {"--set", true, true}, {"--out"}, {"--time-budget"}, {"--write-meshes"}, {"--variant"}, {"--reference", false}, {"--form"}, {"--profile"}, {"--quiet", false},
             {"--save-state"}, {"--frame-of-state"}, {"--load-state"}, {"--append", false}, {"--reference-file"},
             {"--memory-limit"}});
  // Everything is checked before anything is written.
  const std::string scene = args.require("--scene");
  const std::string out = args.require("--out");
  std::vector<std::string> sets;
  if (args.has("--variant")) sets.push_back("variant=" + args.get("--variant"));  // explicit --set keys win
  if (args.has("--frames")) sets.push_back("frames=" + args.get("--frames"));
  for (const auto& s : args.all("--set")) sets.push_back(s);
  // State checkpoints (harness/io/state_io.hpp): save after frame F (frames raised to F + 1).
  const std::string save_state = args.get("--save-state", "");
  int state_frame = -1;
  if (args.has("--frame-of-state") != !save_state.empty())
    throw Error("run: --save-state FILE and --frame-of-state F go together");
  if (!save_state.empty()) {
    state_frame = args.get_int("--frame-of-state", 0);
    if (state_frame < 0 || state_frame >= max_frames)
      throw Error("run: --frame-of-state " + std::to_string(state_frame) + " is out of range [0, " + std::to_string(max_frames - 1) + "]");
  }
  Params p = resolve_params(scene, sets, args.get("--profile", ""));  // scene < profile < --set
  if (state_frame >= p.frames) p.frames = state_frame + 1;  // the run must reach frame F
  const auto runs = method_runs(parse_methods(args.require("--solver")), args.get("--form", ""));
  if (!save_state.empty() && runs.size() != 1) throw Error("run: --save-state needs exactly one solver (one trajectory)");
  // Inputs are never outputs; output folders are made (or refused) now, not after the runs.
  std::vector<std::string> inputs = mesh_inputs(p);
  inputs.push_back(resolve_scene(scene));
  if (args.has("--profile")) inputs.push_back(resolve_profile(args.get("--profile")));
  if (args.has("--load-state")) inputs.push_back(args.get("--load-state"));
  if (args.has("--reference-file")) inputs.push_back(args.get("--reference-file"));  // read, and written beside out
  check_output("run", "--out", out, inputs);
  ResultsWriter writer = command_writer("run", out, args.has("--append"));  // replaces out unless --append
  if (!save_state.empty()) {
    inputs.push_back(out);  // the state must not land on the results either
    check_output("run", "--save-state", save_state, inputs);
  }
  if (args.has("--write-meshes")) check_output_dir("run", "--write-meshes", args.get("--write-meshes"), inputs);
  std::optional<SimState> loaded;
  if (args.has("--load-state")) loaded = read_state(args.get("--load-state"));
  RunOptions opt = run_options(args);
  const Problem prob = build_problem(p);
  if (loaded && loaded->x.cols() != prob.particles.size())
    throw Error("run: --load-state " + args.get("--load-state") + " has " + std::to_string(loaded->x.cols()) +
                " particles, scene '" + p.scene + "' has " + std::to_string(prob.particles.size()));
  opt.initial_state = loaded ? &*loaded : nullptr;

  const bool show = progress_wanted(args);
  int index = 0;
  std::vector<RunRecord> added;  // reported at the end (the file may hold many more)
  for (const auto& [method, form, tag] : runs) {
    Params q = p;
    if (!form.empty()) q.form = form;
    const std::string head = "run: " + p.scene + " with " + tag + " ...";
    std::cerr << head << std::flush;
    ProgressLine line(show, head);
    RunOptions run_opt = opt;
    const std::string which = runs.size() > 1 ? "run " + std::to_string(index + 1) + "/" + std::to_string(runs.size()) : "";
    run_opt.on_iteration = [&line, which](const IterationProgress& s) { line.set_iteration(s, which); };
    std::optional<WriteError> failed;  // a mesh or state that could not be written ends the command
    add_frame_writers(run_opt, args, prob, p.scene + "_" + tag, save_state, state_frame, q, failed);
    const RunResult res = run_simulation(prob, q, method, run_opt);
    line.stop();
    std::cerr << " " << res.status << " (" << res.outer_iterations << " outer iterations, " << res.wall_time << " s)\n";
    if (failed) throw command_write_error("run", *failed, out, writer.runs_in_file());
    ++index;
    added.push_back(make_simulation_record(p.scene + "_" + tag, q, method, res));
    added.back().name = append_command_run("run", writer, added.back(), writer.runs_in_file());
  }
  close_command_writer("run", writer);
  print_runs(added, "table");
  return 0;
}

int cmd_report(const CommandArgs& argv) {
  Args args("report", argv, {{"--format"}}, 1);
  if (args.positional().empty()) throw Error("report: which results file? (report FILE.h5 [--format table|json])");
  const std::string format = args.get("--format", "table");
  if (format != "table" && format != "json") throw Error("report: unknown format '" + format + "' (valid: table, json)");
  // Unreadable runs are named on stderr and skipped; the exit code says some were.
  return print_report(args.positional()[0], format) > 0 ? 1 : 0;
}

int cmd_repair(const CommandArgs& argv) {
  Args args("repair", argv, {}, 1);
  if (args.positional().empty()) throw Error("repair: which results file? (repair FILE.h5)");
  const std::string path = args.positional()[0];
  const RepairReport rep = repair_results(path);
  print_repair(path, rep);
  return 0;
}

int cmd_pack(const CommandArgs& argv) {
  Args args("pack", argv, {{"--out"}}, 1);
  if (args.positional().empty()) throw Error("pack: which results file? (pack FILE.h5 --out ONE.h5)");
  const std::string src = args.positional()[0], out = args.require("--out");
  check_output("pack", "--out", out, {src});
  check_replaceable("pack", out);
  if (!is_results_file(src)) throw Error("pack: " + src + " is not an xpbd-bench results file (no group /runs)");
  std::vector<std::string> skipped;
  try {
    skipped = pack_runs(src, out);
  } catch (const WriteError& e) {
    throw WriteError(e.path, e.err, std::string("pack: ") + e.what());
  }
  warn_skipped("pack", skipped);
  std::cout << "pack: wrote " << out << " (" << count_runs(out) << " runs, one file)\n";
  return skipped.empty() ? 0 : 1;  // as report: some runs could not be read
}

}  // namespace xb
