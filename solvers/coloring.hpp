// Greedy graph colouring of a symmetric CSR pattern, in row order: deterministic, so any
// method parallelised over colours gives the same result for every thread count.
#pragma once

#include "../core/sparse.hpp"

#include <vector>

namespace xb {

struct Coloring {
  int num_colors = 0;
  std::vector<int> color;        // per row
  std::vector<int> color_start;  // rows of colour c are order[color_start[c] .. color_start[c+1])
  std::vector<int> order;
};

// Rows i and j get different colours when A_ij is stored (i ≠ j).
Coloring greedy_coloring(const SparseMatrix& A);

}  // namespace xb
