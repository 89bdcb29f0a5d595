#include "hierarchy.hpp"

#include "../../problems/error.hpp"
#include "../../problems/params.hpp"
#include "strength.hpp"

namespace xb::amg {

AmgOptions AmgOptions::from_params(const Params& p) {
  AmgOptions o;
  o.strength_threshold = p.amg_strength_threshold;
  o.aggregation = p.amg_aggregation;
  o.near_kernel.kind = p.amg_near_kernel;
  o.near_kernel.sweeps = p.amg_near_kernel_sweeps;
  o.near_kernel.vectors = p.amg_near_kernel_vectors;
  o.near_kernel.seed = static_cast<unsigned>(p.seed);
  o.smoother.kind = p.amg_smoother;
  o.smoother.sweeps = p.amg_smoother_sweeps;
  o.smoother.seed = static_cast<unsigned>(p.seed);
  o.max_coarse = p.amg_max_coarse;
  o.max_levels = p.amg_max_levels;
  return o;
}

void Hierarchy::setup(const SparseMatrix& A, const AmgOptions& opt) {
  if (A.rows() != A.cols()) throw Error("mgpbd: the matrix is not square");
  if (opt.max_levels < 1) throw Error("amg.max_levels must be >= 1");
  if (opt.max_coarse < 1) throw Error("amg.max_coarse must be >= 1");
  const AggregationRule rule = aggregation_rule(opt.aggregation);  // validate names up front
  opt_ = opt;
  levels_.clear();
  levels_.emplace_back();
  levels_[0].A = &A;
  Eigen::MatrixXd B;
  for (;;) {
    Level& L = levels_.back();
    const SparseMatrix& Al = *L.A;
    const int n = static_cast<int>(Al.rows());
    if (static_cast<int>(levels_.size()) >= opt.max_levels || n <= opt.max_coarse) break;
    if (levels_.size() == 1) B = near_kernel_candidates(Al, opt.near_kernel);
    const SparseMatrix S = strength_symmetric(Al, opt.strength_threshold);
    Aggregates agg = rule(S);
    if (agg.num_aggregates == 0) break;  // every row isolated: nothing to coarsen onto
    Tentative T = tentative_prolongator(agg, B);
    const int nc = static_cast<int>(T.P.cols());
    if (nc == 0 || nc >= n) break;       // no coarsening progress
    Level next;
    L.one_candidate = T.max_row_entries <= 1;
    if (L.one_candidate)
      L.galerkin.build(Al, T.P, T.R, next.A_own);
    else
      next.A_own = galerkin_product(T.R, Al, T.P);
    B = T.B_coarse;
    L.aggregates = std::move(agg);
    L.T = std::move(T);
    levels_.push_back(std::move(next));
    levels_.back().A = &levels_.back().A_own;
  }
  // std::vector may have moved the levels: re-point the coarse matrices at their own storage.
  for (size_t l = 1; l < levels_.size(); ++l) levels_[l].A = &levels_[l].A_own;
  for (size_t l = 0; l + 1 < levels_.size(); ++l) levels_[l].smoother = make_smoother(opt.smoother, *levels_[l].A);
  factor_coarsest();
}

void Hierarchy::refresh(const SparseMatrix& A) {
  if (levels_.empty()) throw Error("mgpbd: refresh before setup");
  if (A.rows() != levels_[0].A->rows() || A.nonZeros() != levels_[0].A->nonZeros())
    throw Error("mgpbd: refresh with a different sparsity pattern (a full setup is needed)");
  levels_[0].A = &A;
  for (size_t l = 0; l + 1 < levels_.size(); ++l) {
    Level& L = levels_[l];
    Level& next = levels_[l + 1];
    if (L.one_candidate)
      L.galerkin.refresh(*L.A, next.A_own);
    else
      next.A_own = galerkin_product(L.T.R, *L.A, L.T.P);
    L.smoother->refresh(*L.A);
  }
  factor_coarsest();
}

void Hierarchy::factor_coarsest() {
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
  if (dense_coarse_)
    x = dense_llt_.solve(b);
  else
    x = sparse_ldlt_.solve(b);
}

double Hierarchy::operator_complexity() const {
  if (levels_.empty()) return 0;
  double s = 0;
  for (const auto& L : levels_) s += static_cast<double>(L.A->nonZeros());
  return s / static_cast<double>(levels_[0].A->nonZeros());
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
