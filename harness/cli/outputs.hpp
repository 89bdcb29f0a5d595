// Inputs are never outputs: every file a command writes is checked, before anything runs, against
// every file it reads (by filesystem identity, not by spelling) and against what it may replace.
#pragma once

#include "../params.hpp"
#include "../io/atomic_file.hpp"
#include "../io/record.hpp"

#include <string>
#include <vector>

namespace xb {

// The mesh files the parameters make a scene read: both files of a TetGen pair, the cached
// pair of a named real mesh; none for a generator.
std::vector<std::string> mesh_inputs(const Params& p);

// Refuses an output path (given with `flag`) that names a directory, lies under a folder that
// cannot be made (it is made now), or is one of `inputs` (PATH.tmp included). Throws xb::Error.
void check_output(const std::string& command, const std::string& flag, const std::string& out,
                  const std::vector<std::string>& inputs);
// A folder that per-frame files go to: made now; refused when it is a file or one of `inputs`.
void check_output_dir(const std::string& command, const std::string& flag, const std::string& dir,
                      const std::vector<std::string>& inputs);

// Whether `path` is an HDF5 file with a link /runs (an xpbd-bench results file).
bool is_results_file(const std::string& path);
// run and solve replace --out: refused unless it is absent or a results file.
void check_replaceable(const std::string& command, const std::string& out);

// append_runs for a command: a failed write (a full disk) is rethrown as one line that starts
// with the command and says how many runs the file still holds (`kept`: its runs before this
// write), then `hint` (what to do next) if given. The file itself is left as it was.
void append_command_run(const std::string& command, const std::string& out, const RunRecord& run, bool fresh,
                        int kept, const std::string& hint = "");
// That line for any failed write of a command: "<command>: <e>; <holder> holds the <kept> runs
// finished before<hint>".
WriteError command_write_error(const std::string& command, const WriteError& e, const std::string& holder, int kept,
                               const std::string& hint = "");

}  // namespace xb
