// Goldenthal's fast projection: a direct Cholesky solve of the global system with CHOLMOD
// (supernodal LLᵀ). The symbolic analysis (fill-reducing ordering, supernodes) is done once per
// sparsity pattern; the numeric factorisation once per matrix (cholmod.refactor = always).
// cholmod.refactor = lagged: the factor of an earlier matrix preconditions CG on the current one
// (a factor a few outer iterations old is close to the current matrix when the step changes it
// little); it is factorised again at the first setup of every frame, and inside a solve whose CG
// with the old factor needs more than cholmod.lagged_max_iterations (the solve then goes on from
// where that CG stopped, with the new factor).
#include "../factories.hpp"
#include "../kernels.hpp"
#include "../krylov/pcg.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../../core/process_memory.hpp"
#include "../solver_settings.hpp"

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace xb {

namespace {
class CholmodSolver final : public LinearSolver {
 public:
  explicit CholmodSolver(const SolverSettings& p)
      : LinearSolver(p.linear.tol),
        lagged_(p.cholmod.refactor == "lagged"),
        lagged_max_(p.cholmod.lagged_max_iterations),
        max_iterations_(p.linear.max_iterations),
        natural_(p.linear.stop_norm == "energy") {
    cholmod_start(&c_);
    c_.quick_return_if_not_posdef = 1;
    // CHOLMOD's own printing off: its status becomes this solver's message (a breakdown on an
    // indefinite K, which Newton's safeguard retries, printed a warning line per try).
    c_.print = 0;
  }
  ~CholmodSolver() override {
    if (L_) cholmod_free_factor(&L_, &c_);
    cholmod_finish(&c_);
  }
  std::string name() const override { return "cholmod"; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override {
    Timer t;
    A_ = &A;
    // A row-major CSR of a symmetric matrix is, read as CSC, the same matrix; stype = 1 tells
    // CHOLMOD to use the upper triangle and ignore the rest (no copy).
    view_ = {};
    view_.nrow = view_.ncol = A.rows();
    view_.nzmax = A.nonZeros();
    view_.p = const_cast<int*>(A.outerIndexPtr());
    view_.i = const_cast<int*>(A.innerIndexPtr());
    view_.x = const_cast<double*>(A.valuePtr());
    view_.stype = 1;
    view_.itype = CHOLMOD_INT;
    view_.xtype = CHOLMOD_REAL;
    view_.dtype = CHOLMOD_DOUBLE;
    view_.sorted = 1;
    view_.packed = 1;
    if (kind == SetupKind::Structure || !L_) {
      if (L_) cholmod_free_factor(&L_, &c_);
      Timer ta;
      L_ = cholmod_analyze(&view_, &c_);
      analyse_time_ += ta.seconds();
      check_factor_fits();
      factorise("analyse+factorise");
    } else if (lagged_ && factor_ok_ && ctx.frame == factor_frame_) {
      fresh_ = false;  // keep the factor of an earlier matrix
      action_ = "lagged";
      ++lagged_setups_;
    } else {
      factorise("factorise");
    }
    factor_frame_ = ctx.frame;
    setup_time_ = t.seconds();
  }

  bool set_relative_residual(RelativeResidual rel) override {
    rel_ = std::move(rel);
    return lagged_;  // the exact solve has no loop to judge with; the caller refines it
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    LinearStats st;
    if (lagged_ && factor_ok_) {
      st = solve_lagged(b, x);
    } else {
      st = solve_exact(b, x);
    }
    st.setup_time = setup_time_;
    setup_time_ = 0;
    return st;
  }

  // The factor's solve: exactly A⁻¹ of the last factorised matrix (lagged: an earlier one).
  Preconditioner preconditioner() override {
    if (!factor_ok_) return nullptr;
    return [this](const Vector& r, Vector& z) {
      if (!apply_factor(r, z)) z = Vector::Constant(r.size(), std::numeric_limits<double>::quiet_NaN());
    };
  }

  std::map<std::string, double> statistics() const override {
    std::map<std::string, double> s;
    if (L_) {
      s["factor_nnz"] = c_.lnz;
      s["factor_flops"] = c_.fl;
    }
    s["factorisations"] = factorisations_;
    s["factorise_time_total"] = factorise_time_;
    s["analyse_time_total"] = analyse_time_;
    if (lagged_) {
      s["lagged_setups"] = lagged_setups_;
      s["refactorisations_in_solve"] = refactors_in_solve_;
    }
    return s;
  }
  std::string last_setup_action() const override { return action_; }

 private:
  // The symbolic analysis knows nnz(L) before the numeric factorisation allocates it: where the
  // process has a memory limit (`run --memory-limit`) that the factor would pass, the run ends as
  // out of memory now, not after CHOLMOD has tried.
  void check_factor_fits() const {
    const long long limit = data_limit_bytes();
    if (!L_ || limit < 0) return;
    const double need = c_.lnz * (sizeof(double) + sizeof(int)) + static_cast<double>(std::max(0LL, data_bytes()));
    if (need > static_cast<double>(limit))
      throw OutOfMemory("CHOLMOD's factor would not fit the memory limit of " + gigabytes(static_cast<double>(limit)) +
                        ": its " + std::to_string(static_cast<long long>(c_.lnz)) + " non-zeros (symbolic analysis) and the " +
                        "process's data segment need " + gigabytes(need));
  }

  void factorise(const char* action) {
    Timer t;
    factor_ok_ = L_ && cholmod_factorize(&view_, L_, &c_) && c_.status == CHOLMOD_OK;
    if (c_.status == CHOLMOD_OUT_OF_MEMORY) throw OutOfMemory(out_of_memory());  // the run's status: out_of_memory
    if (!L_)
      message_ = "CHOLMOD analysis failed";
    else if (c_.status == CHOLMOD_NOT_POSDEF)
      message_ = "matrix not positive definite (CHOLMOD failed at column " + std::to_string(L_->minor) + ")";
    else if (!factor_ok_)
      message_ = "CHOLMOD factorisation failed (status " + std::to_string(c_.status) + ")";
    fresh_ = true;
    action_ = action;
    ++factorisations_;
    factorise_time_ += t.seconds();
  }

  // Where CHOLMOD ran out of memory, with the factor's size where the analysis got that far.
  std::string out_of_memory() const {
    if (!L_) return "out of memory in CHOLMOD's analysis of a " + std::to_string(view_.nrow) + "-row matrix";
    char mb[32];
    std::snprintf(mb, sizeof mb, "%.0f", c_.lnz * (sizeof(double) + sizeof(int)) / 1e6);
    return "out of memory in CHOLMOD's factorisation: the factor needs " + std::to_string(static_cast<long long>(c_.lnz)) +
           " non-zeros (about " + mb + " MB)";
  }

  // x = L⁻ᵀL⁻¹ b with the current factor; false if CHOLMOD failed; OutOfMemory (the run's status
  // out_of_memory) where it ran out of memory.
  bool apply_factor(const Vector& b, Vector& x) {
    cholmod_dense bd{};
    bd.nrow = b.size();
    bd.ncol = 1;
    bd.nzmax = b.size();
    bd.d = b.size();
    bd.x = const_cast<double*>(b.data());
    bd.xtype = CHOLMOD_REAL;
    bd.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* xd = cholmod_solve(CHOLMOD_A, L_, &bd, &c_);
    if (!xd && c_.status == CHOLMOD_OUT_OF_MEMORY)
      throw OutOfMemory("out of memory in CHOLMOD's solve with a factor of " +
                        std::to_string(static_cast<long long>(c_.lnz)) + " non-zeros");
    if (!xd) return false;
    x.resize(b.size());
    std::copy(static_cast<double*>(xd->x), static_cast<double*>(xd->x) + b.size(), x.data());
    cholmod_free_dense(&xd, &c_);
    return true;
  }

  LinearStats solve_exact(const Vector& b, Vector& x) {
    LinearStats st;
    Timer t;
    const double bnorm = norm2(b);
    st.residual_history.push_back(bnorm);
    st.residual_time.push_back(0);
    x = Vector::Zero(b.size());
    if (!factor_ok_) {
      st.status = LinearStatus::breakdown;
      st.message = message_;
      return st;
    }
    if (!apply_factor(b, x)) {
      st.status = LinearStatus::breakdown;
      st.message = "CHOLMOD solve failed";
      return st;
    }
    st.solve_time = t.seconds();
    Vector r;
    residual(*A_, x, b, r);
    const double rnorm = norm2(r);
    st.iterations = 1;
    st.residual_history.push_back(rnorm);
    st.residual_time.push_back(st.solve_time);
    st.final_relative_residual = bnorm > 0 ? rnorm / bnorm : 0;
    if (!std::isfinite(rnorm)) {
      st.status = LinearStatus::breakdown;
      st.message = "solution is not finite";
    }
    return st;
  }

  // CHOLMOD's solve failed inside the preconditioner: caught in solve_lagged.
  struct SolveFailed {};

  // CG preconditioned by the factor; with an old factor at most lagged_max_iterations, then a
  // new factor and CG again on what is left (b − Ax), judged against the original b. A failed
  // CHOLMOD solve ends it as a breakdown; running out of memory in either, as OutOfMemory.
  LinearStats solve_lagged(const Vector& b, Vector& x) {
    Timer t;
    LinearStats st;
    try {
      st = lagged_cg(b, x, t);
    } catch (const SolveFailed&) {
      st.status = LinearStatus::breakdown;
      st.message = "CHOLMOD solve failed";
      x = Vector::Zero(b.size());
    }
    st.solve_time = t.seconds();
    return st;
  }

  LinearStats lagged_cg(const Vector& b, Vector& x, const Timer& t) {
    const double bnorm = norm2(b);
    const RelativeResidual judge = rel_ ? rel_ : RelativeResidual([bnorm](const Vector& r) { return norm2(r) / bnorm; });
    Preconditioner M = [this](const Vector& r, Vector& z) {
      if (!apply_factor(r, z)) throw SolveFailed{};
    };
    const bool stale = !fresh_;
    LinearStats st = pcg(*A_, b, x, M, tolerance(), stale ? lagged_max_ : max_iterations_, judge, natural_);
    if (st.status != LinearStatus::max_iterations || !stale) return st;
    // The old factor was not good enough: factorise A and solve for the rest.
    factorise("lagged+factorise");
    ++refactors_in_solve_;
    if (!factor_ok_) {
      st.status = LinearStatus::breakdown;
      st.message = message_;
      return st;
    }
    Vector r, dx;
    residual(*A_, x, b, r);
    const double rnorm = norm2(r);
    double tol = tolerance();
    if (natural_) {  // the same stop test as one CG from zero: relative to b's natural norm
      Vector zb, zr;
      M(b, zb);
      M(r, zr);
      tol *= std::sqrt(std::max(0.0, dot(b, zb)) / std::max(1e-300, dot(r, zr)));
    }
    const double t0 = t.seconds();
    LinearStats more = pcg(*A_, r, dx, M, tol, max_iterations_, judge, natural_);
    x += dx;
    // pcg logs judge(r)·‖its b‖: in units of the original ‖b‖ from here on.
    for (size_t k = 1; k < more.residual_history.size(); ++k) {
      st.residual_history.push_back(more.residual_history[k] * bnorm / std::max(rnorm, 1e-300));
      st.residual_time.push_back(t0 + more.residual_time[k]);
    }
    st.iterations += more.iterations;
    st.status = more.status;
    st.message = more.message;
    Vector rtrue;
    residual(*A_, x, b, rtrue);
    st.final_relative_residual = judge(rtrue);
    return st;
  }

  cholmod_common c_{};
  cholmod_factor* L_ = nullptr;
  cholmod_sparse view_{};
  const SparseMatrix* A_ = nullptr;
  const bool lagged_;
  const int lagged_max_, max_iterations_;
  const bool natural_;
  RelativeResidual rel_;
  bool factor_ok_ = false, fresh_ = false;
  int factor_frame_ = -1;
  std::string message_, action_;
  double setup_time_ = 0, analyse_time_ = 0, factorise_time_ = 0;
  int factorisations_ = 0, lagged_setups_ = 0, refactors_in_solve_ = 0;
};
}  // namespace

std::unique_ptr<LinearSolver> make_cholmod(const SolverSettings& p) { return std::make_unique<CholmodSolver>(p); }

}  // namespace xb
