// The tentative (unsmoothed) prolongator: per aggregate, a thin QR of the candidates restricted
// to it, B_a = Q_a R_a. P holds the Q_a blocks (orthonormal columns per aggregate, one row block
// per aggregate), the stacked R_a are the next level's candidates, so P·B_coarse = B.
// A candidate that is (numerically) a combination of earlier ones on an aggregate adds no
// column there, so P has full column rank and PᵀAP stays positive definite.
#pragma once

#include "aggregation.hpp"

#include <Eigen/Dense>
#include <vector>

namespace xb::amg {

struct Tentative {
  SparseMatrix P;              // n × n_c
  SparseMatrix R;              // Pᵀ, built directly (the restriction of the V-cycle)
  Eigen::MatrixXd B_coarse;    // n_c × k
  std::vector<int> col_start;  // per aggregate: its first coarse column (size num_aggregates + 1)
  int max_row_entries = 0;     // 1 ⇒ the one-candidate Galerkin path applies
};

// dst takes src's arrays (core/sparse.hpp's take: a plain move would copy P and R).
using xb::take;
inline void take(Tentative& dst, Tentative&& src) {
  take(dst.P, std::move(src.P));
  take(dst.R, std::move(src.R));
  dst.B_coarse = std::move(src.B_coarse);
  dst.col_start = std::move(src.col_start);
  dst.max_row_entries = src.max_row_entries;
}

// B: n × k candidates. A column is dropped on an aggregate when what is left of it after
// orthogonalisation is below drop_tol times its norm there.
Tentative tentative_prolongator(const Aggregates& agg, const Eigen::MatrixXd& B, double drop_tol = 1e-10);

}  // namespace xb::amg
