// The gs smoother: multicolour Gauss–Seidel, forward sweeps before, backward sweeps after (so the
// post-smoother is the pre-smoother's A-adjoint).
#pragma once

#include "../../coloring.hpp"
#include "smoother.hpp"

namespace xb::amg {

// One multicolour Gauss–Seidel sweep on A x = b: colours in order (forward) or reversed
// (backward); rows of one colour are independent and updated in parallel.
void multicolor_gs_sweep(const SparseMatrix& A, const Vector& inv_diag, const Coloring& coloring, const Vector& b,
                         Vector& x, bool forward);

class GaussSeidelSmoother final : public Smoother {
 public:
  GaussSeidelSmoother(const SmootherOptions& opt, const SparseMatrix& A);
  std::string name() const override { return "gs"; }
  bool symmetric_from_zero() const override { return false; }
  void refresh(const SparseMatrix& A) override;
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override;
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override;

 private:
  SmootherOptions opt_;
  Coloring coloring_;
  Vector inv_diag_;
};

}  // namespace xb::amg
