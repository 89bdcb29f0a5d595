// The AMG hierarchy (Algorithm 1 + Galerkin operators): strength → aggregation → tentative P
// per level until a level has ≤ max_coarse rows or max_levels levels exist; A_{l+1} = Pᵀ A_l P;
// a smoother per level; a direct (Cholesky) solve on the coarsest level.
// setup() builds everything; refresh() keeps aggregates and P and recomputes only what depends
// on A's values (the lazy setup of the paper): A_l by the precomputed Galerkin map, diagonals,
// spectral bounds, the coarse factorisation.
#pragma once

#include "aggregation.hpp"
#include "galerkin.hpp"
#include "near_kernel.hpp"
#include "smoothers.hpp"
#include "tentative.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <memory>
#include <string>
#include <vector>

namespace xb {
struct Params;
}

namespace xb::amg {

struct AmgOptions {
  double strength_threshold = 0.25;
  std::string aggregation = "standard";
  NearKernelOptions near_kernel;
  SmootherOptions smoother;
  int max_coarse = 400;
  int max_levels = 10;
  // The amg.* keys of a Params (amg.strength_threshold, amg.aggregation, amg.near_kernel*,
  // amg.smoother*, amg.max_coarse, amg.max_levels, seed).
  static AmgOptions from_params(const Params& p);
};

struct Level {
  const SparseMatrix* A = nullptr;  // level 0: the caller's matrix; coarser: &A_own
  SparseMatrix A_own;
  Aggregates aggregates;            // of this level's rows (empty on the coarsest)
  Tentative T;                      // P: this level → the next (empty on the coarsest)
  bool one_candidate = false;       // the aggregate-sum Galerkin path builds the next A
  AggregateGalerkin galerkin;
  std::unique_ptr<Smoother> smoother;
  Vector x, b, r;                   // V-cycle work vectors
};

class Hierarchy {
 public:
  void setup(const SparseMatrix& A, const AmgOptions& opt);
  // A: same pattern as at setup(), new values. Throws xb::Error if the pattern size changed.
  void refresh(const SparseMatrix& A);
  // One V-cycle from x = 0 (Algorithm 2): x ≈ A⁻¹ b. The operator b ↦ x is symmetric positive
  // definite for every smoother, so it can precondition CG. Defined in vcycle.cpp.
  void vcycle(const Vector& b, Vector& x);

  bool empty() const { return levels_.empty(); }
  void clear() { levels_.clear(); }
  int num_levels() const { return static_cast<int>(levels_.size()); }
  const Level& level(int l) const { return levels_[l]; }
  const SparseMatrix& matrix(int l) const { return *levels_[l].A; }
  const AmgOptions& options() const { return opt_; }
  double operator_complexity() const;  // Σ nnz(A_l) / nnz(A_0)
  double grid_complexity() const;      // Σ rows(A_l) / rows(A_0)
  std::vector<double> level_rows() const;
  std::vector<double> level_nnz() const;

 private:
  void factor_coarsest();
  void coarse_solve(const Vector& b, Vector& x);

  AmgOptions opt_;
  std::vector<Level> levels_;
  // Coarsest level: dense Cholesky while small (the usual case, ≤ max_coarse rows), sparse LDLᵀ
  // when max_levels stopped the coarsening early.
  static constexpr int kDenseCoarseLimit = 1500;
  bool dense_coarse_ = true;
  Eigen::LLT<Eigen::MatrixXd> dense_llt_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> sparse_ldlt_;
};

}  // namespace xb::amg
