// The AMG hierarchy (Algorithm 1 + Galerkin operators): strength → aggregation → tentative P
// (optionally smoothed: P = (I − ωD⁻¹A)T) per level until a level has ≤ max_coarse rows or
// max_levels levels exist; A_{l+1} = Pᵀ A_l P; a smoother per level; a direct (Cholesky) solve on
// the coarsest level. Block systems (the primal form, block_size 3) are coarsened by nodes
// (nodal.hpp) on every level.
// setup() builds everything; refresh() keeps aggregates and P and recomputes only what depends
// on A's values (the lazy setup of the paper): A_l by the cached Galerkin pattern, diagonals,
// spectral bounds, the coarse factorisation. The authors' variants: coarse_solver = smoother (the
// coarsest level gets its smoother's sweeps from zero instead of a Cholesky solve) and
// jacobi_omega = level0 (jacobi/chebyshev use level 0's λ_max(D⁻¹A) on every level; a smoothed
// P still uses its level's own). A smoothed P is kept too: it was built from the
// setup's values, which changes the preconditioner, not its correctness.
#pragma once

#include "aggregation.hpp"
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
#include <memory>
#include <string>
#include <vector>

namespace xb {
struct SolverSettings;
}

namespace xb::amg {

struct AmgOptions {
  double strength_threshold = 0.25;   // θ_s of scalar (dual) coarsening
  // θ_s of nodal coarsening (block systems, on block Frobenius norms). 0 keeps every coupling, as
  // pyamg's smoothed aggregation does by default: 0.25 isolates half the cloth's particles (an
  // off-diagonal block of K is about a quarter of its diagonal block there) and shrinks the bar's
  // aggregates to ~4 particles (operator complexity 7.7).
  double nodal_strength_threshold = 0.0;
  // θ_s of nodal coarsening on levels ≥ 1 (< 0: nodal_strength_threshold). Galerkin operators of
  // a smoothed P couple neighbours of neighbours, so θ = 0 there merges ~25 aggregates into one
  // (squash bunny:12k: 924 → 36 rows, 54 PCG iterations); 0.1 gives 924 → 156 and 36 iterations.
  double coarse_nodal_strength_threshold = 0.1;
  // A nodal aggregation with fewer than this many nodes per aggregate coarsens too slowly: a
  // smoothed P then fills the next operator in. On levels ≥ 1 it is first redone at θ = 0 (the
  // stretched bar, bar_hang r16, went 792 → 286 nodes at θ = 0.1, its level 2 43% dense); if it
  // is still below (on any level: couplings along lines only, as the filtered bar's), its
  // aggregates are aggregated again on the graph of their couplings until it is not. 0 = never.
  double min_coarsening = 4;
  // Block systems, level 0: node blocks below this fraction of their diagonals' geometric mean
  // are dropped, their norms lumped onto the diagonal (zero_filter.hpp). Round-off zeros are
  // ≤ 1e-14 there (bar_hang); the smallest real coupling on the captured systems is 3e-6 (squash
  // bunny:50k). 0 = keep every block.
  double drop_tolerance = 1e-10;
  std::string aggregation = "standard";
  NearKernelOptions near_kernel;      // kind "auto": rigid on a block system with a basis, else ones
  std::string prolongator = "auto";   // auto (smoothed on block systems, else tentative) | tentative | smoothed
  // D of the smoothed P. Block (a scalar layout's blocks are its diagonal): the same or fewer
  // iterations than the scalar D on the captured primal systems (squash 29 against 31), and the
  // block smoother's λ_max(D⁻¹A) serves P too (one Lanczos per level, not two).
  JacobiDiagonal prolongator_diagonal = JacobiDiagonal::Block;
  // kind "auto": kBlockSmoother on a block system, else chebyshev; sweeps 0: kBlockSmootherSweeps
  // on a block system, else 1; degree 0: kBlockChebyshevDegree on a block system, else 3.
  SmootherOptions smoother;
  int max_coarse = 400;
  int max_levels = 10;
  std::string coarse_solver = "direct";   // direct | smoother
  std::string jacobi_omega = "per_level";  // per_level | level0
  // Storage of the V-cycle: "double", or "single" (float copies of every level's A, P, R and of
  // its polynomial smoother, made at setup and refresh; the coarsest solve stays double).
  std::string precision = "double";
  // The amg.* keys of a SolverSettings (amg.strength_threshold, amg.nodal_strength_threshold,
  // amg.coarse_nodal_strength_threshold, amg.min_coarsening, amg.drop_tolerance, amg.aggregation, amg.near_kernel*,
  // amg.prolongator, amg.prolongator_diagonal, amg.smoother*, amg.chebyshev_degree,
  // amg.max_coarse, amg.max_levels, amg.coarse_solver, amg.jacobi_omega, amg.precision, seed).
  static AmgOptions from_settings(const SolverSettings& p);
};

// What amg.smoother = auto, amg.smoother_sweeps = 0 and amg.chebyshev_degree = 0 take on block
// systems (the primal form): one sweep of a degree-4 Chebyshev in D_block⁻¹A. Per decade of
// residual it is cheaper than degree 3 × 2 on every captured system (docs/kernels.md, "Smoother
// cost per digit": four passes before and after instead of six, for 0–30% more iterations);
// degree 3 × 1 is cheaper still but leaves the stretched bar above a fifth of dual jacobi-pcg's
// iterations. Block Gauss–Seidel costs about twice as much per decade there.
inline constexpr const char* kBlockSmoother = "block_chebyshev";
inline constexpr int kBlockSmootherSweeps = 1;
inline constexpr int kBlockChebyshevDegree = 4;

// What the caller knows about the matrix beyond its entries (SetupContext's fields).
struct MatrixInfo {
  int block_size = 1;                          // unknowns per node, node-major
  const Eigen::MatrixXd* near_kernel = nullptr;  // n × k basis (rigid-body modes), setup only
};

// Throws xb::Error naming the amg.* key of an unknown aggregation, near-kernel, prolongator or
// smoother name, coarse solver or omega rule (the check a solver makes when it is created).
void check_option_names(const AmgOptions& opt);
// The options with "auto" resolved for this matrix (near_kernel = gs_authors makes an auto
// prolongator smoothed, as the authors hand their candidates to smoothed aggregation); throws
// xb::Error for unknown names, near_kernel = rigid without a basis and jacobi_omega = level0 with
// a smoother other than jacobi or chebyshev.
AmgOptions resolve_options(const AmgOptions& opt, const MatrixInfo& info);

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
  // opt may hold "auto" kinds: they are resolved against info (options() returns the result).
  void setup(const SparseMatrix& A, const AmgOptions& opt, const MatrixInfo& info = {});
  // A: same pattern as at setup(), new values. Throws xb::Error if the pattern size changed.
  // Returns false, with only level 0 refreshed, when level 0 dropped blocks (amg.drop_tolerance)
  // that A's values no longer make negligible: the hierarchy is stale and a full setup is due.
  bool refresh(const SparseMatrix& A);
  // One V-cycle from x = 0 (Algorithm 2): x ≈ A⁻¹ b. The operator b ↦ x is symmetric positive
  // definite for every smoother, so it can precondition CG. Defined in vcycle.cpp.
  void vcycle(const Vector& b, Vector& x);

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
  void finish_levels();
  // amg.precision = single: the float copies of the levels (after setup and refresh) and the
  // V-cycle on them (vcycle.cpp).
  void make_single();
  void vcycle_single(const Vector& b, Vector& x);
  void coarse_solve(const Vector& b, Vector& x);
  // jacobi_omega = level0: level 0's λ_max on every coarser level's smoother.
  void share_level0_lambda();

  AmgOptions opt_;  // resolved
  MatrixInfo info_;
  std::vector<Level> levels_;
  ZeroBlockFilter filter_;  // level 0's A_F, when blocks were dropped
  bool filtered() const { return filter_.dropped_blocks() > 0; }
  long fine_nnz_ = 0;       // the caller's A
  // Coarsest level: dense Cholesky while small (the usual case, ≤ max_coarse rows), sparse LDLᵀ
  // when max_levels stopped the coarsening early.
  static constexpr int kDenseCoarseLimit = 1500;
  bool dense_coarse_ = true;
  Eigen::LLT<Eigen::MatrixXd> dense_llt_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> sparse_ldlt_;
};

}  // namespace xb::amg
