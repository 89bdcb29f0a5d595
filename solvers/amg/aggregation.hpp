// Aggregation: partitions the rows of a strength graph S into aggregates (the coarse unknowns).
// Rules are chosen by name (amg.aggregation) and share one signature, so another rule (e.g. a
// parallel MIS-2 aggregation) slots in next to the standard one.
#pragma once

#include "../../core/sparse.hpp"

#include <string>
#include <vector>

namespace xb::amg {

struct Aggregates {
  int num_aggregates = 0;
  std::vector<int> aggregate;  // per row: its aggregate, or -1 (isolated: no strong neighbour)
  std::vector<int> roots;      // per aggregate: the row it was grown from
};

using AggregationRule = Aggregates (*)(const SparseMatrix& S);

// Vaněk's greedy standard aggregation (pyamg's standard_aggregation), on the off-diagonal
// pattern of S, in row order, so it is deterministic:
//  1. a row whose strong neighbours are all unaggregated becomes a root; it and its
//     neighbours form an aggregate (a row with no strong neighbour is isolated: aggregate −1);
//  2. each left-over row joins the first pass-1 aggregate among its neighbours;
//  3. each row still left starts a new aggregate with its still-unaggregated neighbours.
Aggregates standard_aggregation(const SparseMatrix& S);

// The rule called `name` (valid: "standard"); throws xb::Error naming amg.aggregation otherwise.
AggregationRule aggregation_rule(const std::string& name);

}  // namespace xb::amg
