// The AMG hierarchy (Algorithm 1 + Galerkin operators): strength → aggregation → tentative P
// (optionally smoothed: P = (I − ωD⁻¹A)T) per level until a level has ≤ max_coarse rows or
// max_levels levels exist; A_{l+1} = Pᵀ A_l P; a smoother per level; a direct (Cholesky) solve on
// the coarsest level. Block systems (the primal form, block_size 3) are coarsened by nodes
// (nodal.hpp) on every level.
// setup() (configure + build) builds everything; refresh() keeps aggregates and P and recomputes only what depends
// on A's values (the lazy setup of the paper): A_l by the cached Galerkin pattern, diagonals,
// spectral bounds, the coarse factorisation. The authors' variants: coarse_solver = smoother (the
// coarsest level gets its smoother's sweeps from zero instead of a Cholesky solve) and
// jacobi_omega = level0 (jacobi/chebyshev use level 0's λ_max(D⁻¹A) on every level; a smoothed
// P still uses its level's own). A smoothed P is kept too: it was built from the
// setup's values, which changes the preconditioner, not its correctness.
#pragma once

#include "aggregation.hpp"
#include "amg_settings.hpp"
#include "block_kernels.hpp"
#include "galerkin.hpp"
#include "near_kernel.hpp"
#include "nodal.hpp"
#include "smoothed_prolongator.hpp"
#include "relaxation/smoothers.hpp"
#include "tentative.hpp"
#include "zero_filter.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace xb::amg {

// A level in single precision (amg.precision = single).
struct SingleLevel {
  CsrOf<float> A, P, R;
  DiagonalRelaxation<float> relax;
  VectorOf<float> x, b, r;  // V-cycle work vectors
};

struct Level {
  const SparseMatrix* A = nullptr;  // level 0: the caller's matrix; coarser: &A_own
  SparseMatrix A_own;
  Aggregates aggregates;            // of this level's rows (empty on the coarsest)
  NodeLayout nodes;                 // this level's nodes (scalar: one row each)
  Tentative T;                      // P (tentative or smoothed) and R: this level → the next
  bool one_candidate = false;       // the aggregate-sum Galerkin path builds the next A
  AggregateGalerkin galerkin;
  GalerkinProduct product;          // otherwise: the general product with its cached pattern
  std::unique_ptr<Smoother> smoother;
  // Block levels: A, P and R by node blocks for the V-cycle's kernels and the block smoothers
  // (null or empty where the matrix is not node-block CSR: the scalar kernels run then). A's on
  // the heap: its smoother keeps a pointer while the levels vector grows.
  std::unique_ptr<BlockOperator> A_blocks;
  BlockOperator P_blocks, R_blocks;
  Vector x, b, r;                   // V-cycle work vectors
  SingleLevel single;               // amg.precision = single only
};

class Hierarchy {
 public:
  // Resolves opt against info (resolve_options, once; options() returns the result) and keeps
  // both for build(). Throws xb::Error for bad options: bad input, found before any numerical work.
  void configure(const AmgOptions& opt, const MatrixInfo& info = {});
  // Every level from A with the configured options (info's near kernel is read here, not kept).
  void build(const SparseMatrix& A);
  void setup(const SparseMatrix& A, const AmgOptions& opt, const MatrixInfo& info = {}) {
    configure(opt, info);
    build(A);
  }
  // A: same pattern as at build(), new values. Throws xb::Error if the pattern size changed.
  // With amg.coarse_refresh_interval = k > 1 only every k-th refresh after build() recomputes
  // the coarse levels; the others refresh level 0's smoother alone.
  // Returns false, with only level 0 refreshed, when level 0 dropped blocks (amg.drop_tolerance)
  // that A's values no longer make negligible: the hierarchy is stale and a full setup is due.
  bool refresh(const SparseMatrix& A);
  // The same for level 0's smoother (and its float copy) alone: the coarse levels are kept as
  // the last refresh left them (a lagged coarse correction, still SPD; amg.refresh = fine).
  bool refresh_fine(const SparseMatrix& A);
  // One V-cycle from x = 0 (Algorithm 2): x ≈ A⁻¹ b. The operator b ↦ x is symmetric positive
  // definite for every smoother, so it can precondition CG. Defined in vcycle.cpp.
  void vcycle(const Vector& b, Vector& x);

  // Whether the V-cycle reads level 0 from its own storage (the float copy of precision =
  // single, or A_F of drop_tolerance), not the caller's matrix: then values changed in the
  // caller's matrix leave the preconditioner as it was (amg.refresh = keep).
  bool owns_level0() const { return !levels_.empty() && (opt_.precision == "single" || filtered()); }
  bool empty() const { return levels_.empty(); }
  void clear() { levels_.clear(); }
  int num_levels() const { return static_cast<int>(levels_.size()); }
  const Level& level(int l) const { return levels_[l]; }
  const SparseMatrix& matrix(int l) const { return *levels_[l].A; }
  const AmgOptions& options() const { return opt_; }
  // Σ nnz(A_l) / nnz(A), A the caller's matrix (level 0 holds A_F where amg.drop_tolerance dropped blocks).
  double operator_complexity() const;
  double grid_complexity() const;      // Σ rows(A_l) / rows(A_0)
  std::vector<double> level_rows() const;
  std::vector<double> level_nnz() const;

 private:
  // Builds level l+1 from level l; false when level l cannot be coarsened (it stays coarsest).
  bool coarsen(Eigen::MatrixXd& B);
  void factor_coarsest();
  // A's node blocks on a block level (null where A is not node-block CSR): for the node graph of
  // the aggregation, the block smoothers, the prolongator and the V-cycle's kernels.
  void build_level_blocks(Level& L);
  // Level l's smoother (block levels read A by its node blocks).
  void make_level_smoother(Level& L);
  // After setup or refresh: the coarsest level's factor (coarse_solver = direct), the shared λ of
  // jacobi_omega = level0, then the float copies of precision = single, which take that λ.
  // fine_levels < num_levels(): only levels [0, fine_levels) changed (a lagged refresh): the
  // coarsest factor and the coarser float copies are kept.
  void finish_levels(size_t fine_levels = SIZE_MAX);
  // amg.precision = single: the float copies of the levels (after setup and refresh) and the
  // V-cycle on them (vcycle.cpp).
  void make_single(size_t fine_levels = SIZE_MAX);
  void vcycle_single(const Vector& b, Vector& x);
  void coarse_solve(const Vector& b, Vector& x);
  // jacobi_omega = level0: level 0's λ_max on every coarser level's smoother.
  void share_level0_lambda();

  AmgOptions opt_;  // resolved
  MatrixInfo info_;
  std::vector<Level> levels_;
  ZeroBlockFilter filter_;  // level 0's A_F, when blocks were dropped
  bool filtered() const { return filter_.dropped_blocks() > 0; }
  // refresh()'s checks and level 0's matrix (A, or A_F refreshed); false: A_F is stale.
  bool refresh_level0(const SparseMatrix& A);
  long fine_nnz_ = 0;       // the caller's A
  long refreshes_ = 0;      // values-only refreshes since the last build (coarse_refresh_interval)
  // Coarsest level: dense Cholesky while small (the usual case, ≤ max_coarse rows), sparse LDLᵀ
  // when max_levels stopped the coarsening early.
  static constexpr int kDenseCoarseLimit = 1500;
  bool dense_coarse_ = true;
  Eigen::LLT<Eigen::MatrixXd> dense_llt_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> sparse_ldlt_;
};

}  // namespace xb::amg
