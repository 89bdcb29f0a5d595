#include "node_layout.hpp"

#include "../../core/error.hpp"

#include <string>

namespace xb::amg {

NodeLayout NodeLayout::uniform(int rows, int block_size) {
  if (block_size < 1 || rows % block_size != 0)
    throw Error("block size " + std::to_string(block_size) + " does not divide the " + std::to_string(rows) + " rows");
  NodeLayout l;
  l.node_start.resize(rows / block_size + 1);
  for (size_t I = 0; I < l.node_start.size(); ++I) l.node_start[I] = static_cast<int>(I) * block_size;
  return l;
}

}  // namespace xb::amg
