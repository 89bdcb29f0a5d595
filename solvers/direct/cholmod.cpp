// Goldenthal's fast projection: a direct Cholesky solve of the global dual system with CHOLMOD
// (supernodal LLᵀ). The symbolic analysis (fill-reducing ordering, supernodes) is done once per
// sparsity pattern; the numeric factorisation once per matrix.
#include "../factories.hpp"
#include "../kernels.hpp"
#include "../timer.hpp"

#include "../../core/error.hpp"
#include "../solver_settings.hpp"

#include <cholmod.h>

#include <cmath>

namespace xb {

namespace {
class CholmodSolver final : public LinearSolver {
 public:
  CholmodSolver() { cholmod_start(&c_); c_.quick_return_if_not_posdef = 1; }
  ~CholmodSolver() override {
    if (L_) cholmod_free_factor(&L_, &c_);
    cholmod_finish(&c_);
  }
  std::string name() const override { return "cholmod"; }

  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext&) override {
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
    action_ = "factorise";
    if (kind == SetupKind::Structure || !L_) {
      if (L_) cholmod_free_factor(&L_, &c_);
      L_ = cholmod_analyze(&view_, &c_);
      action_ = "analyse+factorise";
    }
    factor_ok_ = L_ && cholmod_factorize(&view_, L_, &c_) && c_.status == CHOLMOD_OK;
    if (!L_)
      message_ = "CHOLMOD analysis failed";
    else if (c_.status == CHOLMOD_NOT_POSDEF)
      message_ = "matrix not positive definite (CHOLMOD failed at column " + std::to_string(L_->minor) + ")";
    else if (!factor_ok_)
      message_ = "CHOLMOD factorisation failed (status " + std::to_string(c_.status) + ")";
    setup_time_ = t.seconds();
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    LinearStats st;
    st.setup_time = setup_time_;
    setup_time_ = 0;
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
    cholmod_dense bd{};
    bd.nrow = b.size();
    bd.ncol = 1;
    bd.nzmax = b.size();
    bd.d = b.size();
    bd.x = const_cast<double*>(b.data());
    bd.xtype = CHOLMOD_REAL;
    bd.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* xd = cholmod_solve(CHOLMOD_A, L_, &bd, &c_);
    if (!xd) {
      st.status = LinearStatus::breakdown;
      st.message = "CHOLMOD solve failed";
      return st;
    }
    std::copy(static_cast<double*>(xd->x), static_cast<double*>(xd->x) + b.size(), x.data());
    cholmod_free_dense(&xd, &c_);
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

  std::map<std::string, double> statistics() const override {
    std::map<std::string, double> s;
    if (L_) {
      s["factor_nnz"] = c_.lnz;
      s["factor_flops"] = c_.fl;
    }
    return s;
  }
  std::string last_setup_action() const override { return action_; }

 private:
  cholmod_common c_{};
  cholmod_factor* L_ = nullptr;
  cholmod_sparse view_{};
  const SparseMatrix* A_ = nullptr;
  bool factor_ok_ = false;
  std::string message_, action_;
  double setup_time_ = 0;
};
}  // namespace

std::unique_ptr<LinearSolver> make_cholmod(const SolverSettings&) { return std::make_unique<CholmodSolver>(); }

}  // namespace xb
