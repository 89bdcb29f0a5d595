#include "coloring.hpp"

#include <algorithm>

namespace xb {

Coloring greedy_coloring(const SparseMatrix& A) {
  const int n = static_cast<int>(A.rows());
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  Coloring c;
  c.color.assign(n, -1);
  std::vector<int> used;  // used[col] == i marks colour col taken by a neighbour of row i
  for (int i = 0; i < n; ++i) {
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      const int j = cols[k];
      if (j != i && c.color[j] >= 0) {
        if (c.color[j] >= static_cast<int>(used.size())) used.resize(c.color[j] + 1, -1);
        used[c.color[j]] = i;
      }
    }
    int col = 0;
    while (col < static_cast<int>(used.size()) && used[col] == i) ++col;
    c.color[i] = col;
    c.num_colors = std::max(c.num_colors, col + 1);
  }
  c.color_start.assign(c.num_colors + 1, 0);
  for (int i = 0; i < n; ++i) ++c.color_start[c.color[i] + 1];
  for (int k = 0; k < c.num_colors; ++k) c.color_start[k + 1] += c.color_start[k];
  c.order.resize(n);
  std::vector<int> pos(c.color_start.begin(), c.color_start.end() - 1);
  for (int i = 0; i < n; ++i) c.order[pos[c.color[i]]++] = i;
  return c;
}

namespace {
// Colour lists from per-vertex colours (−1: not coloured).
void finish(Coloring& c) {
  const int n = static_cast<int>(c.color.size());
  c.color_start.assign(c.num_colors + 1, 0);
  for (int i = 0; i < n; ++i)
    if (c.color[i] >= 0) ++c.color_start[c.color[i] + 1];
  for (int k = 0; k < c.num_colors; ++k) c.color_start[k + 1] += c.color_start[k];
  c.order.resize(c.color_start[c.num_colors]);
  std::vector<int> pos(c.color_start.begin(), c.color_start.end() - 1);
  for (int i = 0; i < n; ++i)
    if (c.color[i] >= 0) c.order[pos[c.color[i]]++] = i;
}
}  // namespace

Coloring element_vertex_coloring(int n, const std::vector<std::array<int, 4>>& elements, const std::vector<char>& active) {
  std::vector<int> start(n + 1, 0);
  for (const auto& e : elements)
    for (int v : e)
      if (v >= 0) ++start[v + 1];
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> inc(start[n]), pos(start.begin(), start.end() - 1);
  for (int k = 0; k < static_cast<int>(elements.size()); ++k)
    for (int v : elements[k])
      if (v >= 0) inc[pos[v]++] = k;
  Coloring c;
  c.color.assign(n, -1);
  std::vector<int> used;  // used[col] == i: colour col is taken by a neighbour of vertex i
  for (int i = 0; i < n; ++i) {
    if (!active[i]) continue;
    for (int k = start[i]; k < start[i + 1]; ++k)
      for (int v : elements[inc[k]])
        if (v >= 0 && v != i && c.color[v] >= 0) {
          if (c.color[v] >= static_cast<int>(used.size())) used.resize(c.color[v] + 1, -1);
          used[c.color[v]] = i;
        }
    int col = 0;
    while (col < static_cast<int>(used.size()) && used[col] == i) ++col;
    c.color[i] = col;
    c.num_colors = std::max(c.num_colors, col + 1);
  }
  finish(c);
  return c;
}

}  // namespace xb
