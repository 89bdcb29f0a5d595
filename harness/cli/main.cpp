// xpbd-bench: the command-line entry point. Bad input ends with one line naming what is wrong
// and exit code 2; nothing already written is lost.
#include "commands.hpp"
#include "sweep_jobs.hpp"
#include "wait_policy.hpp"

#include "../../core/error.hpp"
#include "../../solvers/mpi/distributed.hpp"

#include <mpi.h>

#include <cstring>
#include <iostream>
#include <string>

namespace {
struct Command {
  const char* name;
  int (*fn)(const xb::CommandArgs&);
  const char* usage;
};
const Command commands[] = {
    {"list", xb::cmd_list, "list                                  scenes, solvers and parameter keys, one per line"},
    {"schema", xb::cmd_schema, "schema                                the results schema as JSON (results/schema.json)"},
    {"run", xb::cmd_run,
     "run --scene NAME|FILE --solver A,B,... [--frames N] [--profile NAME|FILE] [--set key=value]... [--time-budget S] [--memory-limit GB] [--reference] [--reference-file FILE] [--save-state FILE --frame-of-state F] [--load-state FILE] --out FILE.h5 [--append]"},
    {"report", xb::cmd_report, "report FILE.h5 [--format table|json]"},
    {"sweep", xb::cmd_sweep, "sweep SPEC.toml --out FILE.h5 [--size NAME] [--profile NAME|FILE] [--time-budget S] [--jobs N | --part K/N]   (resumes: skips runs already in FILE; under mpirun the ranks share the jobs)"},
    {"capture", xb::cmd_capture,
     "capture --scene NAME|FILE [--set key=value]... --frame F [--substep S] --iteration I [--solver X] [--time-budget S] --out PREFIX"},
    {"solve", xb::cmd_solve, "solve --system PREFIX.h5 --solver A,B,... [--tol T] [--set key=value]... --out FILE.h5 [--append]"},
    {"pack", xb::cmd_pack, "pack FILE.h5 --out ONE.h5                 every run of FILE in one self-contained file (to hand to someone)"},
    {"repair", xb::cmd_repair, "repair FILE.h5                            rebuild FILE's index from its run files; say what was found"},
};

// A command's exit code; an error is one line (with the rank under mpirun) and exit code 2 (3 for a bug).
int run_command(int (*fn)(const xb::CommandArgs&), int argc, char** argv) {
  const std::string who = xb::mpi_size() > 1 && xb::mpi_rank() > 0 ? "xpbd-bench: rank " + std::to_string(xb::mpi_rank()) + ": " : "xpbd-bench: ";
  try {
    return fn(xb::CommandArgs(argv + 2, argv + argc));
  } catch (const xb::Error& e) {
    std::cerr << who << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << who << "internal error: " << e.what() << "\n";
    return 3;
  }
}

void usage(std::ostream& os) {
  os << "usage: xpbd-bench COMMAND [options]\n";
  for (const auto& c : commands) os << "  " << c.usage << "\n";
}
}  // namespace

int main(int argc, char** argv) {
  xb::ensure_bounded_wait_policy(argv);
  xb::limit_blas_threads();
  xb::note_cli_program();
  MPI_Init(&argc, &argv);
  // Under mpirun, ranks > 0 serve the distributed solvers (hypre, muelu) of rank 0; a sweep's
  // ranks first share its jobs (cmd_sweep.cpp), then serve until rank 0 ends.
  if (xb::mpi_rank() > 0) {
    int rc = 0;
    if (argc >= 2 && !std::strcmp(argv[1], "sweep")) rc = run_command(xb::cmd_sweep, argc, argv);
    const int wrc = xb::serve_workers();
    xb::finalize_external_libraries();
    MPI_Finalize();
    return rc ? rc : wrc;
  }
  int rc = 0;
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage(argc < 2 ? std::cerr : std::cout);
    rc = argc < 2 ? 2 : 0;
  } else {
    const std::string name = argv[1];
    const Command* cmd = nullptr;
    for (const auto& c : commands)
      if (name == c.name) cmd = &c;
    if (!cmd) {
      std::string valid;
      for (const auto& c : commands) valid += (valid.empty() ? "" : ", ") + std::string(c.name);
      std::cerr << "xpbd-bench: unknown command '" << name << "' (valid: " << valid << ")\n";
      rc = 2;
    } else {
      rc = run_command(cmd->fn, argc, argv);
    }
  }
  xb::stop_workers();
  xb::finalize_external_libraries();
  MPI_Finalize();
  return rc;
}
