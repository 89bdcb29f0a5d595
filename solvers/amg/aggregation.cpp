#include "aggregation.hpp"

#include "../../core/error.hpp"

namespace xb::amg {

Aggregates standard_aggregation(const SparseMatrix& S) {
  const int n = static_cast<int>(S.rows());
  const int* outer = S.outerIndexPtr();
  const int* cols = S.innerIndexPtr();
  constexpr int kFree = -2, kIsolated = -1;
  Aggregates out;
  std::vector<int>& agg = out.aggregate;
  agg.assign(n, kFree);

  // Pass 1 is greedy in row order (each root depends on every earlier one): sequential by
  // nature, and O(nnz), so it costs about one SpMV.
  for (int i = 0; i < n; ++i) {
    if (agg[i] != kFree) continue;
    bool has_neighbors = false, neighbor_taken = false;
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      const int j = cols[k];
      if (j == i) continue;
      has_neighbors = true;
      if (agg[j] != kFree) {
        neighbor_taken = true;
        break;
      }
    }
    if (!has_neighbors) {
      agg[i] = kIsolated;
    } else if (!neighbor_taken) {
      const int a = out.num_aggregates++;
      out.roots.push_back(i);
      agg[i] = a;
      for (int k = outer[i]; k < outer[i + 1]; ++k) agg[cols[k]] = a;
    }
  }
  const int pass1 = out.num_aggregates;

  // Pass 2: attach left-overs to a neighbouring pass-1 aggregate. Reads only pass-1 results
  // (written to a copy), so rows are independent: parallel.
  std::vector<int> joined(n, kFree);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    if (agg[i] != kFree) continue;
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      const int a = agg[cols[k]];
      if (a >= 0 && a < pass1) {
        joined[i] = a;
        break;
      }
    }
  }
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i)
    if (joined[i] != kFree) agg[i] = joined[i];

  // Pass 3: whatever is left grows new aggregates with its free neighbours (sequential, greedy).
  for (int i = 0; i < n; ++i) {
    if (agg[i] != kFree) continue;
    const int a = out.num_aggregates++;
    out.roots.push_back(i);
    agg[i] = a;
    for (int k = outer[i]; k < outer[i + 1]; ++k)
      if (agg[cols[k]] == kFree) agg[cols[k]] = a;
  }
  return out;
}

AggregationRule aggregation_rule(const std::string& name) {
  if (name == "standard") return &standard_aggregation;
  throw Error("amg.aggregation: unknown rule '" + name + "' (valid: standard)");
}

}  // namespace xb::amg
