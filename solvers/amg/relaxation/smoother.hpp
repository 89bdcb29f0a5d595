// The V-cycle's smoother interface (the kinds: smoothers.hpp). Each smoother is symmetric in the
// sense CG needs: the post-smoother is the A-adjoint of the pre-smoother, so the V-cycle is a
// symmetric operator.
#pragma once

#include "../../../core/sparse.hpp"
#include "diagonal_relaxation.hpp"

#include <string>

namespace xb::amg {

class BlockDiagonal;

class Smoother {
 public:
  virtual ~Smoother() = default;
  virtual std::string name() const = 0;
  // New values, same pattern: recompute the diagonal and spectral bounds.
  virtual void refresh(const SparseMatrix& A) = 0;
  // `sweeps` times; x_zero says x is zero on entry (saves a matrix product).
  virtual void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) = 0;
  virtual void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) = 0;
  // The λ_max(D⁻¹A) estimate in use (0 for the Gauss–Seidel kinds); D is the scalar diagonal,
  // or the node blocks where block_diagonal() returns them (the smoothed prolongator reuses both).
  virtual double lambda_max() const { return 0; }
  virtual const BlockDiagonal* block_diagonal() const { return nullptr; }
  // jacobi and chebyshev: use this λ_max(D⁻¹A) instead of the level's own estimate until the next
  // refresh (amg.jacobi_omega = level0: level 0's on every level, as the authors do).
  virtual void set_lambda_max(double lambda);
  // presmooth from x = 0 is a symmetric operator of b (polynomials in D⁻¹A times D⁻¹); false for
  // the Gauss–Seidel kinds, whose forward sweeps need the backward ones after them.
  virtual bool symmetric_from_zero() const { return true; }
  // The polynomial kinds' relaxation (jacobi, chebyshev and their block forms; null for the
  // Gauss–Seidel kinds): what the V-cycle's single-precision copy is made from.
  virtual const DiagonalRelaxation<double>* relaxation() const { return nullptr; }
};

struct SmootherOptions {
  std::string kind = "chebyshev";  // jacobi | chebyshev | gs | block_gs | block_jacobi | block_chebyshev
  int sweeps = 1;
  int degree = 3;                     // chebyshev, block_chebyshev
  int power_iterations = 20;          // Lanczos steps at setup
  int refresh_power_iterations = 10;  // Lanczos steps at refresh
  unsigned seed = 1;
};

// jacobi, chebyshev and their block forms: one DiagonalRelaxation (the polynomial in D⁻¹A). A
// derived class sets its D and λ_max (then check_lambda) at construction and refresh; the rest is
// shared.
class PolynomialSmoother : public Smoother {
 public:
  std::string name() const override { return opt_.kind; }
  double lambda_max() const override { return relax_.lambda; }
  const DiagonalRelaxation<double>* relaxation() const override { return &relax_; }
  void presmooth(const SparseMatrix& A, const Vector& b, Vector& x, bool x_zero) override {
    relax_.presmooth(A, b, x, x_zero);
  }
  void postsmooth(const SparseMatrix& A, const Vector& b, Vector& x) override { relax_.postsmooth(A, b, x); }

 protected:
  explicit PolynomialSmoother(const SmootherOptions& opt, bool chebyshev) : opt_(opt) {
    relax_.chebyshev = chebyshev;
    relax_.sweeps = opt.sweeps;
    relax_.degree = opt.degree;
  }
  // Throws naming amg.smoother when λ_max is not a positive number (A not positive definite).
  void check_lambda(const SparseMatrix& A) const;

  SmootherOptions opt_;
  DiagonalRelaxation<double> relax_;
  Vector eigvec_;  // the Lanczos start of the next refresh
};

}  // namespace xb::amg
