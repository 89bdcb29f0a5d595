// Nodal coarsening of block systems (the primal form K: 3 unknowns per particle, node-major).
// Each node's rows form a block; strength and aggregation act on the node graph and the node
// aggregates are expanded back to the unknowns, so x, y and z of one particle always share an
// aggregate and the per-aggregate QR sees whole rigid-body modes.
//  Level 0: uniform blocks of ctx.block_size.
//  Coarse levels: a node is one aggregate of the level above, its unknowns the QR columns kept
//  there (Tentative::col_start). An aggregate where the QR dropped candidates (one particle spans
//  only 3 of the 6 rigid modes, two particles 5) is a smaller node: block sizes may vary, so no
//  column is padded and P keeps full column rank.
#pragma once

#include "aggregation.hpp"
#include "node_layout.hpp"

#include <vector>

namespace xb::amg {

struct BlockPattern;

// The node matrix: entry (I, J) = Frobenius norm of A's block (I, J) (stored entries only).
// Throws xb::Error if the layout does not cover A's rows.
SparseMatrix node_matrix(const SparseMatrix& A, const NodeLayout& nodes);
// The same from A's node-block pattern (no search for the blocks): the same values.
SparseMatrix node_matrix(const SparseMatrix& A, const BlockPattern& blocks);

// Aggregates of nodes → aggregates of rows (an isolated node's rows are isolated; roots become
// the first row of the root node).
Aggregates expand_aggregates(const Aggregates& node_aggregates, const NodeLayout& nodes);

// While the aggregates hold fewer than min_nodes rows of S each on average (S's couplings run
// along lines, say), `rule` aggregates the aggregates on the graph of their couplings in S; stops
// when a round makes no progress. min_nodes 0: agg unchanged.
Aggregates merge_small_aggregates(const SparseMatrix& S, Aggregates agg, AggregationRule rule, double min_nodes);
// Strength (the symmetric rule on the node matrix N), then `rule` on the node graph, then
// merge_small_aggregates with min_nodes, then expansion.
Aggregates aggregate_nodes(const SparseMatrix& N, const NodeLayout& nodes, double theta, AggregationRule rule,
                           double min_nodes = 0);
// The same on A's node_matrix.
Aggregates nodal_aggregation(const SparseMatrix& A, const NodeLayout& nodes, double theta, AggregationRule rule);

}  // namespace xb::amg
