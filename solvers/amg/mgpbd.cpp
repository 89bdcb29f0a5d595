// MGPBD (Algorithm 3): conjugate gradients preconditioned by one V-cycle of the in-house
// aggregation AMG (solvers/amg/), with the paper's lazy setup (SetupPolicy):
//  - full setup (aggregates, P, every level) on SetupKind::Structure, on a new pattern, and at
//    the first setup of a frame amg.setup_interval frames after the last one;
//  - otherwise a values-only refresh (A_l through the cached Galerkin pattern, diagonals,
//    smoother spectral bounds, the coarse factorisation).
// Between rebuilds, amg.refresh chooses how much of the hierarchy a values-only setup refreshes
// (refresh_rule.hpp): every level (full, the default), level 0's smoother (fine), or nothing (keep).
// On the dual system (block size 1) it is the paper's unsmoothed aggregation with B = 1; on the
// primal form's K (block size 3, rigid-body modes given) it defaults to nodal smoothed
// aggregation with the 6 rigid modes (amg.near_kernel = auto, amg.prolongator = auto).
#include "hierarchy.hpp"
#include "refresh_rule.hpp"
#include "../factories.hpp"
#include "../krylov/pcg.hpp"
#include "../setup_policy.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

namespace xb {

namespace {
class MgpbdSolver final : public LinearSolver {
 public:
  explicit MgpbdSolver(const SolverSettings& p)
      : LinearSolver(p.linear.tol),
        opt_(p.amg),
        maxit_(p.linear.max_iterations),
        natural_(p.linear.stop_norm == "energy"),
        policy_(p.amg.setup_interval),
        rule_(p.amg.refresh, p.amg.refresh_growth) {
    opt_.near_kernel.seed = opt_.smoother.seed = static_cast<unsigned>(p.seed);
    check_settings(amg_settings(), opt_, "mgpbd");  // options set in code: fail now, not inside a run
  }
  std::string name() const override { return "mgpbd"; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override {
    Timer t;
    A_ = &A;
    failure_.clear();
    const bool built = !h_.empty() && A.rows() == h_.matrix(0).rows() && A.nonZeros() == nnz0_ &&
                       ctx.block_size == block_size_;
    const bool full = policy_.rebuild(kind, ctx, built);
    // A configuration error (near_kernel = rigid on a system without rigid modes) is bad input,
    // not a numerical failure: configure() lets it propagate as xb::Error. (A refresh keeps the
    // hierarchy's levels; the options it reads are the same.)
    h_.configure(opt_, {ctx.block_size, ctx.near_kernel});
    try {
      // A hierarchy built on couplings that were zero and are not any more is rebuilt too. keep
      // needs a V-cycle that reads its own copy of level 0 (the float one, or A_F): over the
      // caller's new K an old smoother would not be the old, SPD, operator; fine is used there.
      using amg::RefreshScope;
      RefreshScope scope = full ? RefreshScope::full : rule_.next();
      if (scope == RefreshScope::keep && !h_.owns_level0()) scope = RefreshScope::fine;
      if (scope == RefreshScope::keep) {
        action_ = "reuse";
      } else if (scope == RefreshScope::fine && h_.refresh_fine(A)) {
        action_ = "refresh_fine";
      } else if (!full && h_.refresh(A)) {
        action_ = "refresh";
        rule_.refreshed();
      } else {
        h_.build(A);
        nnz0_ = A.nonZeros();
        block_size_ = ctx.block_size;
        policy_.rebuilt(ctx);
        rule_.refreshed();
        action_ = "setup";
      }
    } catch (const Error& e) {
      // Reported as a breakdown by solve(): a failed run is a result, not a crash.
      failure_ = e.what();
      h_.clear();
    }
    setup_time_ = t.seconds();
    if (action_ == "setup") {
      setup_time_total_ += setup_time_;
      ++setup_count_;
    } else if (action_ == "reuse") {
      ++reuse_count_;
    } else {
      refresh_time_total_ += setup_time_;
      ++refresh_count_;
    }
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    LinearStats st;
    if (!A_ || h_.empty()) {
      st.status = LinearStatus::breakdown;
      st.message = failure_.empty() ? "mgpbd: solve() before setup()" : failure_;
      st.setup_time = setup_time_;
      x = Vector::Zero(b.size());
      return st;
    }
    st = pcg(*A_, b, x, preconditioner(), tolerance(), maxit_, rel_, natural_);
    rule_.solved(st.iterations, st.final_relative_residual, st.status != LinearStatus::breakdown);
    st.setup_time = setup_time_;
    setup_time_ = 0;
    return st;
  }

  // One V-cycle (symmetric: it preconditions CG).
  Preconditioner preconditioner() override {
    if (!A_ || h_.empty()) return nullptr;
    return [this](const Vector& r, Vector& z) { h_.vcycle(r, z); };
  }

  bool set_relative_residual(RelativeResidual rel) override {
    rel_ = std::move(rel);
    return true;
  }

  std::map<std::string, double> statistics() const override {
    std::map<std::string, double> s;
    s["levels"] = h_.num_levels();
    s["operator_complexity"] = h_.operator_complexity();
    s["grid_complexity"] = h_.grid_complexity();
    s["single_precision"] = h_.options().precision == "single";  // amg.precision as resolved
    s["setup_time_total"] = setup_time_total_;
    s["refresh_time_total"] = refresh_time_total_;
    s["setup_count"] = setup_count_;
    s["refresh_count"] = refresh_count_;
    s["reuse_count"] = reuse_count_;
    return s;
  }

  std::map<std::string, std::vector<double>> array_statistics() const override {
    return {{"level_rows", h_.level_rows()}, {"level_nnz", h_.level_nnz()}};
  }

  std::string last_setup_action() const override { return action_; }

 private:
  amg::AmgOptions opt_;
  int maxit_;
  bool natural_;
  SetupPolicy policy_;
  amg::RefreshRule rule_;
  RelativeResidual rel_;
  amg::Hierarchy h_;
  const SparseMatrix* A_ = nullptr;
  long nnz0_ = -1;
  int block_size_ = 1;
  std::string action_, failure_;
  double setup_time_ = 0, setup_time_total_ = 0, refresh_time_total_ = 0;
  int setup_count_ = 0, refresh_count_ = 0, reuse_count_ = 0;
};
}  // namespace

std::unique_ptr<LinearSolver> make_mgpbd(const SolverSettings& p) { return std::make_unique<MgpbdSolver>(p); }

}  // namespace xb
