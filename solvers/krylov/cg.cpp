// The iterative baselines: plain CG and Jacobi (diagonally) preconditioned CG.
#include "../factories.hpp"
#include "../kernels.hpp"
#include "pcg.hpp"
#include "../timer.hpp"

#include "../solver_settings.hpp"

namespace xb {

namespace {
class CgSolver final : public LinearSolver {
 public:
  CgSolver(const SolverSettings& p, bool jacobi)
      : LinearSolver(p.linear.tol), maxit_(p.linear.max_iterations), natural_(p.linear.stop_norm == "energy"),
        jacobi_(jacobi) {}
  std::string name() const override { return jacobi_ ? "jacobi-pcg" : "cg"; }

  void setup(const SparseMatrix& A, SetupKind, const SetupContext&) override {
    Timer t;
    A_ = &A;
    if (jacobi_) {
      inv_diag_ = diagonal(A);
      for (long i = 0; i < inv_diag_.size(); ++i) inv_diag_[i] = inv_diag_[i] > 0 ? 1.0 / inv_diag_[i] : 1.0;
    }
    setup_time_ = t.seconds();
  }

  bool set_relative_residual(RelativeResidual rel) override {
    rel_ = std::move(rel);
    return true;
  }

  Preconditioner preconditioner() override {
    if (!jacobi_) return nullptr;
    return [this](const Vector& r, Vector& z) {
      z.resize(r.size());
#pragma omp parallel for schedule(static)
      for (long i = 0; i < r.size(); ++i) z[i] = inv_diag_[i] * r[i];
    };
  }

  LinearStats solve(const Vector& b, Vector& x) override {
    LinearStats st = pcg(*A_, b, x, preconditioner(), tolerance(), maxit_, rel_, natural_);
    st.setup_time = setup_time_;
    setup_time_ = 0;
    return st;
  }

 private:
  int maxit_;
  bool natural_, jacobi_;
  const SparseMatrix* A_ = nullptr;
  Vector inv_diag_;
  RelativeResidual rel_;
  double setup_time_ = 0;
};
}  // namespace

std::unique_ptr<LinearSolver> make_cg(const SolverSettings& p) { return std::make_unique<CgSolver>(p, false); }
std::unique_ptr<LinearSolver> make_jacobi_pcg(const SolverSettings& p) { return std::make_unique<CgSolver>(p, true); }

}  // namespace xb
