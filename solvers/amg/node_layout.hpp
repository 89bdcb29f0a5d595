// The node layout of a block level: which rows form each node (a particle's x, y, z on K; an
// aggregate's kept QR columns on coarse levels). Read by nodal coarsening (nodal.hpp), the node-block
// products (block_sparse.hpp) and the block smoothers (relaxation/).
#pragma once

#include <vector>

namespace xb::amg {

// node_start[I] … node_start[I+1]−1 are node I's rows. Empty means "scalar" (one row per node).
struct NodeLayout {
  std::vector<int> node_start;
  bool scalar() const { return node_start.empty(); }
  int num_nodes() const { return static_cast<int>(node_start.size()) - 1; }
  // Nodes of block_size rows each; throws xb::Error if block_size does not divide rows.
  static NodeLayout uniform(int rows, int block_size);
};

}  // namespace xb::amg
