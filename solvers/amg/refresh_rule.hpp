// amg.refresh: what a values-only setup of mgpbd does between rebuilds (docs/mgpbd.md, "Lazy setup
// and the refresh"). full refreshes every level (A_l by the cached Galerkin products, the
// smoothers, the coarse factor); fine refreshes level 0's smoother alone and keeps the coarse
// levels as they were (a lagged coarse correction: still an SPD preconditioner); keep does no
// work at all (the V-cycle of the last refreshed values preconditions CG on the new matrix).
// A lagged hierarchy is kept while it converges about as fast as a fresh one did: once a solve
// needs more than amg.refresh_growth times the PCG iterations per decade of residual of the first
// solve after the last full refresh, the next setup refreshes every level. Iterations per decade,
// not per solve: under Newton's forcing rule each solve has its own tolerance. Counts only, no
// clocks: the same run makes the same choices on any machine.
#pragma once

#include <string>

namespace xb::amg {

enum class RefreshScope { full, fine, keep };

class RefreshRule {
 public:
  // mode: full | fine | keep (amg.refresh); growth ≥ 1 (amg.refresh_growth).
  RefreshRule(const std::string& mode, double growth);
  // The scope of the next values-only setup: full for mode full, after a breakdown, with no
  // solve since the last full refresh, or when the last solve converged more slowly than
  // growth × the reference; else the mode's.
  RefreshScope next() const;
  // A full refresh or a setup was done: the next solve's rate is the new reference.
  void refreshed() { fresh_ = true; }
  // A solve ended: its PCG iterations and the relative residual it reached; ok = false for a
  // breakdown. A solve of 0 iterations (a zero right-hand side) says nothing and is ignored.
  void solved(int iterations, double relative_residual, bool ok);
  // PCG iterations per decade of relative residual (infinite where it did not drop).
  static double rate(int iterations, double relative_residual);

 private:
  RefreshScope mode_;
  double growth_;
  bool fresh_ = true;       // the next solve sets the reference
  bool known_ = false;      // a solve since the last full refresh has set reference_ and last_
  double reference_ = 0, last_ = 0;
};

}  // namespace xb::amg
