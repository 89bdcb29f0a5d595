// The lazy-setup rule of the paper, in one place for every solver with a hierarchy (mgpbd,
// hypre, muelu): the expensive, pattern-level part (aggregates, P, a BoomerAMG or MueLu
// hierarchy) is rebuilt on a new sparsity pattern, when none exists, and at the first setup of a
// frame at least amg.setup_interval frames after the last rebuild; every other setup() only
// refreshes what depends on the matrix values.
#pragma once

#include "linear_solver.hpp"

#include "../core/error.hpp"

namespace xb {

class SetupPolicy {
 public:
  explicit SetupPolicy(int interval) : interval_(interval) {
    if (interval < 1) throw Error("amg.setup_interval must be >= 1");
  }

  // Whether this setup() must rebuild. `built` says a hierarchy exists for the current pattern.
  bool rebuild(SetupKind kind, const SetupContext& ctx, bool built) const {
    return kind == SetupKind::Structure || !built || ctx.frame >= last_frame_ + interval_ ||
           ctx.frame < last_frame_;
  }
  // Call after a rebuild.
  void rebuilt(const SetupContext& ctx) { last_frame_ = ctx.frame; }
  int interval() const { return interval_; }

 private:
  int interval_;
  int last_frame_ = 0;
};

}  // namespace xb
