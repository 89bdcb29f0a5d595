// Smoothers of the V-cycle. Each one is symmetric in the sense CG needs: the post-smoother is
// the A-adjoint of the pre-smoother, so the V-cycle is a symmetric operator.
//  jacobi:    x += ω D⁻¹(b − Ax), ω = 1/λ_max(D⁻¹A) (the authors' 2/(λ_max+λ_min) with
//             λ_min = λ_max). A fixed ω such as 0.72 diverges on XPBD matrices, where
//             ρ(D⁻¹A) reaches 4–11 (shared/paper/xpbd_matrix_facts.md), so λ_max is estimated.
//  chebyshev: Chebyshev polynomial in D⁻¹A on [ρ/30, 1.1ρ] (the authors' cloth setting, degree 3),
//             ρ estimated per level (the authors reuse level 0's; per level is cheap and safer).
//  gs:        multicolour Gauss–Seidel, forward sweeps before, backward sweeps after.
//  block_gs, block_jacobi, block_chebyshev: the same with D the node blocks of a block system
//             (block_gs.hpp, block_chebyshev.hpp); on a scalar layout D is the diagonal.
// λ_max(D⁻¹A) comes from power iteration with the Rayleigh quotient in the D inner product; a
// values-only refresh warm-starts it from the previous dominant vector.
#pragma once

#include "../../../core/sparse.hpp"
#include "../../coloring.hpp"
#include "../nodal.hpp"
#include "diagonal_relaxation.hpp"

#include <memory>
#include <string>

namespace xb::amg {

class BlockDiagonal;

// Loops shorter than this run on one thread: on coarse levels (tens to hundreds of rows) and in
// small colour classes a parallel region costs more than the work it splits.
constexpr long kMinParallelRows = 2048;

// 1/A_ii (0 where A_ii ≤ 0: such a row is left alone rather than blown up).
Vector inverse_diagonal(const SparseMatrix& A);

// One multicolour Gauss–Seidel sweep on A x = b: colours in order (forward) or reversed
// (backward); rows of one colour are independent and updated in parallel.
void multicolor_gs_sweep(const SparseMatrix& A, const Vector& inv_diag, const Coloring& coloring, const Vector& b,
                         Vector& x, bool forward);

// Upper estimate of λ_max(D⁻¹A) (A SPD): max(iterations, 10) Lanczos steps from v, largest Ritz
// value plus its residual bound, capped by Gershgorin's bound (v is updated to start the next
// estimate; a zero or wrongly sized v is replaced by a seeded random vector).
double estimate_lambda_max(const SparseMatrix& A, const Vector& inv_diag, Vector& v, int iterations,
                           unsigned seed = 1);

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

// The smoother kinds make_smoother knows, for messages: "jacobi, chebyshev, ...".
extern const char* const kSmootherKinds;

// `nodes`: the level's node layout (the block kinds' D; scalar: 1×1 blocks). `blocks`: A's node
// blocks in that layout (not owned, outliving the smoother) for block_jacobi and block_chebyshev
// to read A by, or null. Throws xb::Error naming amg.smoother for an unknown kind.
std::unique_ptr<Smoother> make_smoother(const SmootherOptions& opt, const SparseMatrix& A, const NodeLayout& nodes = {},
                                        const BlockOperator* blocks = nullptr);

}  // namespace xb::amg
