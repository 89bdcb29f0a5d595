#include "block_diagonal.hpp"

#include "lanczos.hpp"

#include "../../../core/error.hpp"
#include "../../../core/reduce.hpp"
#include "../../kernels.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

namespace xb::amg {

namespace {
// inv = D⁻¹ for a b × b row-major SPD block, by Cholesky. Fixed sizes for K's 3×3 nodes and the
// rigid-mode levels' 6×6: a dynamic LLT allocates per node (cloth r160's 25.6K nodes: build()
// 6.0–7.2 ms with it, 3.7 ms without).
template <int B>
bool invert_spd(const double* D, int b, double* inv) {
  using Block = Eigen::Matrix<double, B, B, Eigen::RowMajor>;
  const Eigen::LLT<Eigen::Matrix<double, B, B>> llt(Eigen::Map<const Block>(D, b, b));
  if (llt.info() != Eigen::Success) return false;
  Eigen::Map<Block>(inv, b, b) = llt.solve(Eigen::Matrix<double, B, B>::Identity(b, b));
  return true;
}
}  // namespace

void BlockDiagonal::build(const SparseMatrix& A, const NodeLayout& nodes) {
  const int n = static_cast<int>(A.rows());
  start_ = nodes.scalar() ? NodeLayout::uniform(n, 1).node_start : nodes.node_start;
  if (start_.front() != 0 || start_.back() != n) throw Error("block diagonal: the node layout does not cover the matrix");
  const int nn = num_nodes();
  offset_.assign(nn + 1, 0);
  for (int I = 0; I < nn; ++I) {
    const long b = start_[I + 1] - start_[I];
    offset_[I + 1] = offset_[I] + b * b;
  }
  block_.assign(offset_[nn], 0.0);
  inv_.assign(offset_[nn], 0.0);
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const double* av = A.valuePtr();
  int bad = -1;
#pragma omp parallel for schedule(static) reduction(max : bad)
  for (int I = 0; I < nn; ++I) {
    const int s = start_[I], b = start_[I + 1] - s;
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Db(block_.data() + offset_[I], b, b);
    for (int r = 0; r < b; ++r) {
      // Sorted columns: the block's entries are one contiguous run of the row.
      const int* first = std::lower_bound(ac + ao[s + r], ac + ao[s + r + 1], s);
      for (const int* k = first; k < ac + ao[s + r + 1] && *k < s + b; ++k) Db(r, *k - s) = av[k - ac];
    }
    double* inv = inv_.data() + offset_[I];
    const bool ok = b == 3 ? invert_spd<3>(Db.data(), b, inv) : b == 6 ? invert_spd<6>(Db.data(), b, inv)
                                                                      : invert_spd<Eigen::Dynamic>(Db.data(), b, inv);
    if (b > 0 && !ok) bad = std::max(bad, I);
  }
  if (bad >= 0) throw Error("block diagonal: the diagonal block of node " + std::to_string(bad) + " is not positive definite");
}

namespace {
// Row r of a node's row-major b × b block M times x (the node's part of a vector).
inline double block_row(const double* M, int b, const double* x, int r) {
  double acc = 0;
  for (int c = 0; c < b; ++c) acc += M[r * b + c] * x[c];
  return acc;
}

void apply_blocks(const std::vector<int>& start, const std::vector<long>& offset, const std::vector<double>& blocks,
                  const Vector& x, Vector& y) {
  const int nn = static_cast<int>(start.size()) - 1;
  y.resize(x.size());
#pragma omp parallel for schedule(static) if (nn > kMinParallelRows)
  for (int I = 0; I < nn; ++I) {
    const int s = start[I], b = start[I + 1] - s;
    for (int r = 0; r < b; ++r) y[s + r] = block_row(blocks.data() + offset[I], b, x.data() + s, r);
  }
}
}  // namespace

void BlockDiagonal::apply_inverse(const Vector& x, Vector& y) const { apply_blocks(start_, offset_, inv_, x, y); }
void BlockDiagonal::apply(const Vector& x, Vector& y) const { apply_blocks(start_, offset_, block_, x, y); }

double estimate_lambda_max(const SparseMatrix& A, const BlockDiagonal& D, Vector& v, int iterations, unsigned seed,
                           const BlockOperator* blocks) {
  const long n = A.rows();
  if (n == 0) return 0;
  // Each one parallel pass over the node blocks, no temporaries: xᵀDx, and D⁻¹Aq − a·q − β·q_prev.
  const int nn = D.num_nodes();
  auto dnorm = [&](const Vector& x) {
    const double s = deterministic_sum(nn, [&](long I) {
      const int s0 = D.node_begin(I), b = D.node_end(I) - s0;
      double xDx = 0;
      for (int r = 0; r < b; ++r) xDx += x[s0 + r] * block_row(D.block(I), b, x.data() + s0, r);
      return xDx;
    });
    return std::sqrt(std::max(0.0, s));
  };
  auto step = [&](const Vector& Aq, const Vector& q, const Vector& q_prev, double a, double beta, Vector& w) {
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (int I = 0; I < nn; ++I) {
      const int s0 = D.node_begin(I), b = D.node_end(I) - s0;
      for (int r = 0; r < b; ++r)
        w[s0 + r] = block_row(D.inverse_block(I), b, Aq.data() + s0, r) - a * q[s0 + r] - beta * q_prev[s0 + r];
    }
  };
  const double bound = lanczos_lambda_max(A, v, iterations, seed, dnorm, step, blocks);
  if (std::isnan(bound)) throw Error("block Lanczos: the tridiagonal eigenproblem failed");
  return bound;
}

}  // namespace xb::amg
