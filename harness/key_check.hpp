// No silent no-ops: a key set where nothing reads it is refused, with one message naming the key
// that does that job there (core/key_scope.hpp: every key declares where it has an effect).
//
// Which keys are checked against what:
// - keys the command sets (--set, --variant, --frames, a sweep's [set] and [grid]) must change one
//   of the command's runs (its methods x forms x grid points): a sweep axis that changes nothing, or
//   amg.strength_threshold for mgpbd in the primal form, is refused. The value does not matter:
//   a key set to its default where nothing reads it is refused too, since the user meant something.
// - keys a file sets (the scene file, a profile) must be read by some run of the scene: a scene
//   file or profile is run with every method, form and step (the race runs one scene with
//   xpbd-gs and with mgpbd), so it may hold keys for runs other than this one, but not keys no
//   run of its scene reads (twist in a squash file, compliance in a tet scene).
#pragma once

#include "params.hpp"

#include "../core/key_scope.hpp"

#include <string>
#include <vector>

namespace xb {

// One run of a command, as the key check sees it.
struct CommandRun {
  Params params;
  std::string method;
  bool reference = false;  // run with --reference
  bool solve = false;      // a `solve` run of a captured system ...
  std::string form;        // ... in this resolved form (a simulation run resolves its own)
};

// The form a simulation run's linear step takes: p.form, with auto resolved from the scene's
// compliance; "" for a local method.
std::string resolved_form(const Params& p, const std::string& method);
// The run as the scopes see it (the site reads the run's own parameters).
RunSite run_site(const CommandRun& run);

// Throws xb::Error (where the key was set: message) for the first key that changes nothing.
void check_keys(const std::vector<CommandRun>& runs);

}  // namespace xb
