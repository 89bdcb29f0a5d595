#include "hierarchy.hpp"

#include "../../core/error.hpp"
#include "strength.hpp"

#include <algorithm>

namespace xb::amg {

void Hierarchy::configure(const AmgOptions& opt, const MatrixInfo& info) {
  opt_ = resolve_options(opt, info);
  info_ = info;
}

void Hierarchy::build(const SparseMatrix& A) {
  if (A.rows() != A.cols()) throw Error("mgpbd: the matrix is not square");
  if (opt_.smoother.kind == "auto") throw Error("mgpbd: build() before configure()");
  levels_.clear();
  // Levels are never moved (a move would copy their matrices: core/sparse.hpp's take), and the
  // references coarsen() holds stay valid.
  levels_.reserve(opt_.max_levels);
  levels_.emplace_back();
  levels_[0].A = &A;
  fine_nnz_ = A.nonZeros();
  filter_ = ZeroBlockFilter{};
  refreshes_ = 0;
  if (info_.block_size > 1) {
    Level& L0 = levels_[0];
    L0.nodes = NodeLayout::uniform(static_cast<int>(A.rows()), info_.block_size);
    if (opt_.drop_tolerance > 0) {
      build_level_blocks(L0);
      if (L0.A_blocks && filter_.build(A, L0.A_blocks->pattern, opt_.drop_tolerance)) {
        L0.A = &filter_.matrix();
        L0.A_blocks.reset();  // coarsen() builds A_F's
      }
    }
  }
  Eigen::MatrixXd B;
  while (coarsen(B)) {
  }
  info_.near_kernel = nullptr;  // valid during setup only
  if (opt_.coarse_solver == "smoother") {
    build_level_blocks(levels_.back());
    make_level_smoother(levels_.back());
  }
  finish_levels();
}

void Hierarchy::build_level_blocks(Level& L) {
  L.A_blocks.reset();
  if (L.nodes.scalar()) return;
  L.A_blocks = std::make_unique<BlockOperator>();
  if (!L.A_blocks->build(*L.A, L.nodes, L.nodes)) L.A_blocks.reset();
}

void Hierarchy::make_level_smoother(Level& L) {
  L.smoother = make_smoother(opt_.smoother, *L.A, L.nodes, L.A_blocks.get());
}

void Hierarchy::finish_levels(size_t fine_levels) {
  if (fine_levels >= levels_.size() && opt_.coarse_solver == "direct") factor_coarsest();  // the smoother kind solves with no factor
  if (fine_levels >= levels_.size()) share_level0_lambda();  // a lagged refresh keeps the coarse smoothers as they were
  if (opt_.precision == "single") make_single(fine_levels);  // after the shared λ, which the float copies take
}

void Hierarchy::share_level0_lambda() {
  if (opt_.jacobi_omega != "level0" || !levels_[0].smoother) return;
  const double lambda0 = levels_[0].smoother->lambda_max();
  for (size_t l = 1; l < levels_.size(); ++l)
    if (levels_[l].smoother) levels_[l].smoother->set_lambda_max(lambda0);
}

bool Hierarchy::coarsen(Eigen::MatrixXd& B) {
  Level& L = levels_.back();
  const SparseMatrix& Al = *L.A;
  const int n = static_cast<int>(Al.rows());
  if (static_cast<int>(levels_.size()) >= opt_.max_levels || n <= opt_.max_coarse) return false;
  if (levels_.size() == 1)
    B = near_kernel_candidates(Al, opt_.near_kernel, nullptr, info_.block_size, info_.near_kernel);
  if (!L.A_blocks) build_level_blocks(L);  // level 0's may be built by build()
  const AggregationRule rule = aggregation_rule(opt_.aggregation);
  const double nodal_theta = levels_.size() > 1 && opt_.coarse_nodal_strength_threshold >= 0
                                 ? opt_.coarse_nodal_strength_threshold
                                 : opt_.nodal_strength_threshold;
  SparseMatrix N;  // block levels: the node graph, from A's node blocks where they are built
  if (!L.nodes.scalar()) N = L.A_blocks ? node_matrix(Al, L.A_blocks->pattern) : node_matrix(Al, L.nodes);
  Aggregates agg;
  if (L.nodes.scalar()) {
    agg = rule(strength_symmetric(Al, opt_.strength_threshold));
  } else {
    const bool redo = levels_.size() > 1 && nodal_theta > 0;  // θ = 0 first, then merge
    agg = aggregate_nodes(N, L.nodes, nodal_theta, rule, redo ? 0.0 : opt_.min_coarsening);
    if (redo && L.nodes.num_nodes() < opt_.min_coarsening * agg.num_aggregates)
      agg = aggregate_nodes(N, L.nodes, 0.0, rule, opt_.min_coarsening);
  }
  if (agg.num_aggregates == 0) return false;  // every row isolated: nothing to coarsen onto
  Tentative T = tentative_prolongator(agg, B);
  const int nc = static_cast<int>(T.P.cols());
  if (nc == 0 || nc >= n) return false;       // no coarsening progress
  make_level_smoother(L);
  if (opt_.prolongator == "smoothed") {
    // Where the smoother's D is the prolongator's, its λ_max(D⁻¹A) is reused: no second Lanczos.
    // Its node-block diagonal and A's block pattern as well.
    const bool block_p = opt_.prolongator_diagonal == "block" && !L.nodes.scalar();
    ProlongatorReuse reuse;
    const BlockDiagonal* smoother_D = L.smoother->block_diagonal();
    if ((smoother_D != nullptr) == block_p) {
      reuse.lambda = L.smoother->lambda_max();
      reuse.D = smoother_D;
    }
    if (L.A_blocks) reuse.A_pattern = &L.A_blocks->pattern;
    SmoothedProlongator S = smooth_prolongator(Al, T.P, block_p ? JacobiDiagonal::Block : JacobiDiagonal::Scalar, L.nodes,
                                               opt_.smoother.power_iterations, opt_.smoother.seed,
                                               NodeLayout{T.col_start}, reuse);
    take(T.P, std::move(S.P));
    take(T.R, std::move(S.R));
    if (opt_.prolongator_drop_tolerance > 0 &&
        drop_small_blocks(T.P, L.nodes, NodeLayout{T.col_start}, opt_.prolongator_drop_tolerance) > 0)
      take(T.R, transpose(T.P));
    T.max_row_entries = 0;
    for (int i = 0; i < n; ++i) T.max_row_entries = std::max(T.max_row_entries, static_cast<int>(T.P.row(i).nonZeros()));
  }
  Level& next = levels_.emplace_back();  // no reallocation: build() reserved max_levels
  next.A = &next.A_own;
  if (!L.nodes.scalar()) {
    next.nodes.node_start = T.col_start;  // a coarse node = an aggregate's kept columns
    L.P_blocks.build(T.P, L.nodes, next.nodes);
    L.R_blocks.build(T.R, next.nodes, L.nodes);
  }
  L.one_candidate = T.max_row_entries <= 1;
  if (L.one_candidate)
    L.galerkin.build(Al, T.P, T.R, next.A_own);
  else if (L.A_blocks && !L.P_blocks.empty() && !L.R_blocks.empty())
    L.product.build(T.R, Al, T.P, next.A_own, L.R_blocks.pattern, L.A_blocks->pattern, L.P_blocks.pattern,
                    /*symmetric=*/true);  // A_l is SPD and R = Pᵀ
  else
    L.product.build(T.R, Al, T.P, next.A_own, L.nodes, NodeLayout{T.col_start});
  B = T.B_coarse;
  L.aggregates = std::move(agg);
  take(L.T, std::move(T));
  return true;
}

bool Hierarchy::refresh_level0(const SparseMatrix& A) {
  if (levels_.empty()) throw Error("mgpbd: refresh before setup");
  if (A.rows() != levels_[0].A->rows() || A.nonZeros() != fine_nnz_)
    throw Error("mgpbd: refresh with a different sparsity pattern (a full setup is needed)");
  if (filtered() && !filter_.refresh(A)) return false;
  levels_[0].A = filtered() ? &filter_.matrix() : &A;
  return true;
}

bool Hierarchy::refresh_fine(const SparseMatrix& A) {
  if (!refresh_level0(A)) return false;
  if (levels_.size() == 1) {  // no coarse level to lag: the coarsest is level 0
    if (levels_[0].smoother) levels_[0].smoother->refresh(*levels_[0].A);
    finish_levels();
    return true;
  }
  levels_[0].smoother->refresh(*levels_[0].A);
  finish_levels(1);
  return true;
}

bool Hierarchy::refresh(const SparseMatrix& A) {
  // amg.coarse_refresh_interval: the coarse levels only on every k-th refresh (lagged), level
  // 0's smoother always.
  if (levels_.size() > 1 && ++refreshes_ % opt_.coarse_refresh_interval != 0) return refresh_fine(A);
  if (!refresh_level0(A)) return false;
  for (size_t l = 0; l + 1 < levels_.size(); ++l) {
    Level& L = levels_[l];
    Level& next = levels_[l + 1];
    if (L.one_candidate)
      L.galerkin.refresh(*L.A, next.A_own);
    else
      L.product.refresh(L.T.R, *L.A, L.T.P, next.A_own);
    L.smoother->refresh(*L.A);
  }
  if (levels_.back().smoother) levels_.back().smoother->refresh(*levels_.back().A);
  finish_levels();
  return true;
}

void Hierarchy::factor_coarsest() {
  if (opt_.coarse_solver == "smoother") return;
  const SparseMatrix& Ac = *levels_.back().A;
  const int n = static_cast<int>(Ac.rows());
  dense_coarse_ = n <= kDenseCoarseLimit;
  if (dense_coarse_) {
    dense_llt_.compute(Eigen::MatrixXd(Ac));
    if (dense_llt_.info() != Eigen::Success)
      throw Error("mgpbd: Cholesky of the coarsest level (" + std::to_string(n) + " rows) failed: matrix not positive definite");
  } else {
    Eigen::SparseMatrix<double> Acol = Ac;
    sparse_ldlt_.compute(Acol);
    if (sparse_ldlt_.info() != Eigen::Success)
      throw Error("mgpbd: LDL^T of the coarsest level (" + std::to_string(n) + " rows) failed");
  }
}

void Hierarchy::coarse_solve(const Vector& b, Vector& x) {
  if (opt_.coarse_solver == "smoother") {
    Level& C = levels_.back();
    x.resize(b.size());
    C.smoother->presmooth(*C.A, b, x, true);
    if (!C.smoother->symmetric_from_zero()) C.smoother->postsmooth(*C.A, b, x);
  } else if (dense_coarse_)
    x = dense_llt_.solve(b);
  else
    x = sparse_ldlt_.solve(b);
}

double Hierarchy::operator_complexity() const {
  if (levels_.empty()) return 0;
  double s = 0;
  for (const auto& L : levels_) s += static_cast<double>(L.A->nonZeros());
  return s / static_cast<double>(fine_nnz_);
}

double Hierarchy::grid_complexity() const {
  if (levels_.empty()) return 0;
  double s = 0;
  for (const auto& L : levels_) s += static_cast<double>(L.A->rows());
  return s / static_cast<double>(levels_[0].A->rows());
}

std::vector<double> Hierarchy::level_rows() const {
  std::vector<double> v;
  for (const auto& L : levels_) v.push_back(static_cast<double>(L.A->rows()));
  return v;
}

std::vector<double> Hierarchy::level_nnz() const {
  std::vector<double> v;
  for (const auto& L : levels_) v.push_back(static_cast<double>(L.A->nonZeros()));
  return v;
}

}  // namespace xb::amg
