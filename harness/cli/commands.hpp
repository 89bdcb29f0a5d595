// The sub-commands of xpbd-bench. Each lives in its own harness/cmd_*.cpp.
#pragma once

#include <string>
#include <vector>

namespace xb {
using CommandArgs = std::vector<std::string>;
int cmd_list(const CommandArgs& args);
int cmd_schema(const CommandArgs& args);
int cmd_run(const CommandArgs& args);
int cmd_report(const CommandArgs& args);
int cmd_sweep(const CommandArgs& args);
int cmd_capture(const CommandArgs& args);
int cmd_solve(const CommandArgs& args);
int cmd_pack(const CommandArgs& args);
int cmd_repair(const CommandArgs& args);
}  // namespace xb
