// list, run and report.
#include "args.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "mesh_writer.hpp"

#include "../problems/error.hpp"
#include "../problems/scene.hpp"
#include "../solvers/linear_solver.hpp"

#include <filesystem>
#include <iostream>

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
  return 0;
}

int cmd_run(const CommandArgs& argv) {
  Args args("run", argv,
            {{"--scene"}, {"--solver"}, {"--frames"}, {"--set", true, true}, {"--out"}, {"--time-budget"}, {"--write-meshes"}, {"--variant"}, {"--reference", false}, {"--form"}, {"--profile"}});
  // Everything is checked before anything is written.
  const std::string scene = args.require("--scene");
  const std::string out = args.require("--out");
  std::vector<std::string> sets;
  if (args.has("--variant")) sets.push_back("variant=" + args.get("--variant"));  // explicit --set keys win
  if (args.has("--frames")) sets.push_back("frames=" + args.get("--frames"));
  for (const auto& s : args.all("--set")) sets.push_back(s);
  const Params p = resolve_params(scene, sets, args.get("--profile", ""));  // scene < profile < --set
  const auto runs = method_runs(parse_methods(args.require("--solver")), args.get("--form", ""));
  RunOptions opt;
  opt.time_budget = args.get_double("--time-budget", 0);
  if (opt.time_budget < 0) throw Error("run: --time-budget must be >= 0");
  opt.reference = args.has("--reference");  // per-substep reference and position_error
  const Problem prob = build_problem(p);

  int index = 0;
  for (const auto& [method, form, tag] : runs) {
    Params q = p;
    if (!form.empty()) q.form = form;
    std::cerr << "run: " << p.scene << " with " << tag << " ..." << std::flush;
    RunOptions run_opt = opt;
    if (args.has("--write-meshes")) {  // DIR/<scene>_<solver>_NNNN.ply per frame
      const std::string dir = args.get("--write-meshes");
      run_opt.on_frame = [&, dir](int frame, const Eigen::Matrix3Xd& x) {
        write_ply(frame_ply_path(dir, p.scene + "_" + tag, frame), prob, x);
      };
    }
    const RunResult res = run_simulation(prob, q, method, run_opt);
    std::cerr << " " << res.status << " (" << res.outer_iterations << " outer iterations, " << res.wall_time << " s)\n";
    ++index;
    append_runs(out, {make_simulation_record(run_name(index, p.scene, tag), q, method, res)}, index == 1);
  }
  print_report(out, "table");
  return 0;
}

int cmd_report(const CommandArgs& argv) {
  Args args("report", argv, {{"--format"}}, 1);
  if (args.positional().empty()) throw Error("report: which results file? (report FILE.h5 [--format table|json])");
  const std::string format = args.get("--format", "table");
  if (format != "table" && format != "json") throw Error("report: unknown format '" + format + "' (valid: table, json)");
  print_report(args.positional()[0], format);
  return 0;
}

}  // namespace xb
