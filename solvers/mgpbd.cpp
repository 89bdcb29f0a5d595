// MGPBD (Algorithm 3): conjugate gradients preconditioned by one V-cycle of the in-house
// unsmoothed-aggregation AMG (solvers/amg/), with the paper's lazy setup:
//  - full setup (aggregates, P, every level) on SetupKind::Structure, and at the first setup
//    call of a frame (substep 0, iteration 0) when frame % amg.setup_interval == 0, once per frame;
//  - otherwise a values-only refresh (A_l through the precomputed Galerkin map, diagonals,
//    smoother spectral bounds, the coarse factorisation).
#include "amg/hierarchy.hpp"
#include "amg/vcycle.hpp"
#include "factories.hpp"
#include "pcg.hpp"
#include "timer.hpp"

#include "../problems/error.hpp"
#include "../problems/params.hpp"

namespace xb {

namespace {
class MgpbdSolver final : public LinearSolver {
 public:
  explicit MgpbdSolver(const Params& p)
      : opt_(amg::AmgOptions::from_params(p)),
        tol_(p.linear_tol),
        maxit_(p.linear_max_iterations),
        interval_(p.amg_setup_interval) {
    if (interval_ < 1) throw Error("amg.setup_interval must be >= 1");
    // Fail on bad names now, not at the first setup inside a run.
    amg::aggregation_rule(opt_.aggregation);
    if (opt_.near_kernel.kind != "ones" && opt_.near_kernel.kind != "gs")
      throw Error("amg.near_kernel: unknown kind '" + opt_.near_kernel.kind + "' (valid: ones, gs)");
    if (opt_.smoother.kind != "jacobi" && opt_.smoother.kind != "chebyshev" && opt_.smoother.kind != "gs")
      throw Error("amg.smoother: unknown smoother '" + opt_.smoother.kind + "' (valid: jacobi, chebyshev, gs)");
  }
  std::string name() const override { return "mgpbd"; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override {
    Timer t;
    A_ = &A;
    failure_.clear();
    const bool frame_start = ctx.substep == 0 && ctx.iteration == 0 && ctx.frame % interval_ == 0 &&
                             ctx.frame != last_setup_frame_;
    const bool full = kind == SetupKind::Structure || h_.empty() || frame_start ||
                      A.rows() != h_.matrix(0).rows() || A.nonZeros() != nnz0_;
    try {
      if (full) {
        h_.setup(A, opt_);
        nnz0_ = A.nonZeros();
        last_setup_frame_ = ctx.frame;
        action_ = "setup";
      } else {
        h_.refresh(A);
        action_ = "refresh";
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
    Preconditioner M = [this](const Vector& r, Vector& z) { h_.vcycle(r, z); };
    st = pcg(*A_, b, x, M, tol_, maxit_);
    st.setup_time = setup_time_;
    setup_time_ = 0;
    return st;
  }

  std::map<std::string, double> statistics() const override {
    std::map<std::string, double> s;
    s["levels"] = h_.num_levels();
    s["operator_complexity"] = h_.operator_complexity();
    s["grid_complexity"] = h_.grid_complexity();
    s["setup_time_total"] = setup_time_total_;
    s["refresh_time_total"] = refresh_time_total_;
    s["setup_count"] = setup_count_;
    s["refresh_count"] = refresh_count_;
    return s;
  }

  std::map<std::string, std::vector<double>> array_statistics() const override {
    return {{"level_rows", h_.level_rows()}, {"level_nnz", h_.level_nnz()}};
  }

  std::string last_setup_action() const override { return action_; }

 private:
  amg::AmgOptions opt_;
  double tol_;
  int maxit_;
  int interval_;
  amg::Hierarchy h_;
  const SparseMatrix* A_ = nullptr;
  long nnz0_ = -1;
  int last_setup_frame_ = -1;
  std::string action_, failure_;
  double setup_time_ = 0, setup_time_total_ = 0, refresh_time_total_ = 0;
  int setup_count_ = 0, refresh_count_ = 0;
};
}  // namespace

std::unique_ptr<LinearSolver> make_mgpbd(const Params& p) { return std::make_unique<MgpbdSolver>(p); }

}  // namespace xb
