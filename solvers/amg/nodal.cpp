#include "nodal.hpp"

#include "../../core/error.hpp"
#include "block_sparse.hpp"
#include "strength.hpp"

#include <algorithm>
#include <cmath>

namespace xb::amg {

SparseMatrix node_matrix(const SparseMatrix& A, const NodeLayout& nodes) {
  const int n = static_cast<int>(A.rows());
  if (nodes.scalar() || nodes.node_start.front() != 0 || nodes.node_start.back() != n)
    throw Error("nodal strength: the node layout does not cover the " + std::to_string(n) + " rows");
  const int nn = nodes.num_nodes();
  std::vector<int> node_of(n);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I)
    for (int i = nodes.node_start[I]; i < nodes.node_start[I + 1]; ++i) node_of[i] = I;
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr();
  const double* av = A.valuePtr();
  // Per node row: its node columns (sorted) and Σ a² per column, then the square roots.
  std::vector<std::vector<int>> cols(nn);
  std::vector<std::vector<double>> sq(nn);
#pragma omp parallel
  {
    std::vector<int> pos(nn, -1);
#pragma omp for schedule(dynamic, 256)
    for (int I = 0; I < nn; ++I) {
      std::vector<int>& c = cols[I];
      for (int i = nodes.node_start[I]; i < nodes.node_start[I + 1]; ++i)
        for (int k = ao[i]; k < ao[i + 1]; ++k)
          if (pos[node_of[ac[k]]] < 0) {
            pos[node_of[ac[k]]] = 0;
            c.push_back(node_of[ac[k]]);
          }
      std::sort(c.begin(), c.end());
      for (size_t q = 0; q < c.size(); ++q) pos[c[q]] = static_cast<int>(q);
      std::vector<double>& s = sq[I];
      s.assign(c.size(), 0.0);
      for (int i = nodes.node_start[I]; i < nodes.node_start[I + 1]; ++i)
        for (int k = ao[i]; k < ao[i + 1]; ++k) s[pos[node_of[ac[k]]]] += av[k] * av[k];
      for (int J : c) pos[J] = -1;
    }
  }
  SparseMatrix N(nn, nn);
  int* no = N.outerIndexPtr();
  no[0] = 0;
  for (int I = 0; I < nn; ++I) no[I + 1] = no[I] + static_cast<int>(cols[I].size());
  N.resizeNonZeros(no[nn]);
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I)
    for (size_t q = 0; q < cols[I].size(); ++q) {
      N.innerIndexPtr()[no[I] + q] = cols[I][q];
      N.valuePtr()[no[I] + q] = std::sqrt(sq[I][q]);
    }
  return N;
}

SparseMatrix node_matrix(const SparseMatrix& A, const BlockPattern& blocks) {
  const int nn = blocks.row_nodes();
  const int* ao = A.outerIndexPtr();
  const double* av = A.valuePtr();
  SparseMatrix N(nn, static_cast<int>(blocks.col_start.size()) - 1);
  N.resizeNonZeros(blocks.ptr[nn]);
  std::copy(blocks.ptr.begin(), blocks.ptr.end(), N.outerIndexPtr());
  std::copy(blocks.col.begin(), blocks.col.end(), N.innerIndexPtr());
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I)
    for (int k = blocks.ptr[I]; k < blocks.ptr[I + 1]; ++k) {
      double s = 0;  // row by row, as node_matrix(A, nodes) sums
      for (int r = blocks.row_start[I]; r < blocks.row_start[I + 1]; ++r) {
        const double* a = av + ao[r] + blocks.offset[k];
        for (int q = 0; q < blocks.cols(blocks.col[k]); ++q) s += a[q] * a[q];
      }
      N.valuePtr()[k] = std::sqrt(s);
    }
  return N;
}

Aggregates expand_aggregates(const Aggregates& node_aggregates, const NodeLayout& nodes) {
  const int nn = nodes.num_nodes();
  if (static_cast<int>(node_aggregates.aggregate.size()) != nn) throw Error("nodal aggregation: sizes differ");
  Aggregates out;
  out.num_aggregates = node_aggregates.num_aggregates;
  out.aggregate.resize(nodes.node_start.back());
#pragma omp parallel for schedule(static)
  for (int I = 0; I < nn; ++I)
    for (int i = nodes.node_start[I]; i < nodes.node_start[I + 1]; ++i) out.aggregate[i] = node_aggregates.aggregate[I];
  out.roots.reserve(node_aggregates.roots.size());
  for (int r : node_aggregates.roots) out.roots.push_back(nodes.node_start[r]);
  return out;
}

namespace {
// The graph of the aggregates: a and b adjacent where S couples a node of a to a node of b.
SparseMatrix aggregate_graph(const SparseMatrix& S, const Aggregates& agg) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(S.nonZeros()));
  const int *so = S.outerIndexPtr(), *sc = S.innerIndexPtr();
  for (int i = 0; i < static_cast<int>(S.rows()); ++i) {
    const int a = agg.aggregate[i];
    if (a < 0) continue;
    for (int k = so[i]; k < so[i + 1]; ++k)
      if (agg.aggregate[sc[k]] >= 0) t.emplace_back(a, agg.aggregate[sc[k]], 1.0);
  }
  SparseMatrix C(agg.num_aggregates, agg.num_aggregates);
  C.setFromTriplets(t.begin(), t.end());  // duplicates summed: the pattern is what counts
  return C;
}
}  // namespace

Aggregates merge_small_aggregates(const SparseMatrix& S, Aggregates agg, AggregationRule rule, double min_nodes) {
  const double n = static_cast<double>(S.rows());
  while (min_nodes > 0 && agg.num_aggregates > 1 && n < min_nodes * agg.num_aggregates) {
    const Aggregates merged = rule(aggregate_graph(S, agg));
    if (merged.num_aggregates == 0 || merged.num_aggregates >= agg.num_aggregates) break;  // no progress
    for (int& a : agg.aggregate)
      if (a >= 0) a = merged.aggregate[a];  // an aggregate with no coupled neighbour stays isolated (−1)
    std::vector<int> roots(merged.num_aggregates);
    for (int c = 0; c < merged.num_aggregates; ++c) roots[c] = agg.roots[merged.roots[c]];
    agg.roots = std::move(roots);
    agg.num_aggregates = merged.num_aggregates;
  }
  return agg;
}

Aggregates aggregate_nodes(const SparseMatrix& N, const NodeLayout& nodes, double theta, AggregationRule rule,
                           double min_nodes) {
  const SparseMatrix S = strength_symmetric(N, theta);
  return expand_aggregates(merge_small_aggregates(S, rule(S), rule, min_nodes), nodes);
}

Aggregates nodal_aggregation(const SparseMatrix& A, const NodeLayout& nodes, double theta, AggregationRule rule) {
  return aggregate_nodes(node_matrix(A, nodes), nodes, theta, rule);
}

}  // namespace xb::amg
