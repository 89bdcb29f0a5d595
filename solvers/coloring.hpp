// Greedy graph colouring of a symmetric CSR pattern, in row order: deterministic, so any
// method parallelised over colours gives the same result for every thread count.
#pragma once

#include "../core/sparse.hpp"

#include <array>
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

// The vertices of a mesh of elements (index tuples padded with −1), in index order: two vertices
// that appear in one element get different colours. Only vertices with active[v] != 0 are coloured
// (the others get colour −1 and are not in `order`), and only active vertices conflict: a
// block-descent method updates them, so within one colour no two share an element.
Coloring element_vertex_coloring(int n, const std::vector<std::array<int, 4>>& elements, const std::vector<char>& active);

}  // namespace xb
