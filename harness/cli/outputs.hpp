// Inputs are never outputs: every file a command writes is checked, before anything runs, against
// every file it reads (by filesystem identity, not by spelling) and against what it may replace.
#pragma once

#include "../params.hpp"
#include "../io/atomic_file.hpp"
#include "../io/record.hpp"
#include "../io/recorder.hpp"

#include <string>
#include <vector>

namespace xb {

// The mesh files the parameters make a scene read: both files of a TetGen pair, the cached
// pair of a named real mesh; none for a generator.
std::vector<std::string> mesh_inputs(const Params& p);

// Refuses an output path (given with `flag`) that names a directory, lies under a folder that
// cannot be made (it is made now), or is one of `inputs`. Throws xb::Error (WriteError naming the
// output for a folder that cannot be made or written).
void check_output(const std::string& command, const std::string& flag, const std::string& out,
                  const std::vector<std::string>& inputs);
// A folder that per-frame files go to: made now; refused when it is a file or one of `inputs`.
void check_output_dir(const std::string& command, const std::string& flag, const std::string& dir,
                      const std::vector<std::string>& inputs);

// Whether `path` is an HDF5 file with a link /runs (an xpbd-bench results file).
bool is_results_file(const std::string& path);
// run and solve replace --out: refused unless it is absent or a results file.
void check_replaceable(const std::string& command, const std::string& out);

// Adds one run through a command's writer: a failed write (a full disk) is rethrown as one line
// that starts with the command and says how many runs the file still holds (`kept`: its runs
// before this write), then `hint` (what to do next) if given. The file itself is left as it was.
// Returns the run's name in the file.
std::string append_command_run(const std::string& command, ResultsWriter& out, const RunRecord& run, int kept,
                               const std::string& hint = "");
// `run` and `solve` --out [--append]: refuses an --out that cannot take runs (with --append: one
// that exists and is not a results file; without: check_replaceable) and returns its writer.
ResultsWriter command_writer(const std::string& command, const std::string& out, bool append);
// The writer's close() at the end of a command: a failed write of the index is one line that
// starts with the command and says the runs are kept.
void close_command_writer(const std::string& command, ResultsWriter& out);
// That line for any failed write of a command: "<command>: <e>; <holder> holds the <kept> runs
// finished before<hint>".
WriteError command_write_error(const std::string& command, const WriteError& e, const std::string& holder, int kept,
                               const std::string& hint = "");

}  // namespace xb
