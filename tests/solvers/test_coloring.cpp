// The vertex colouring of block-descent methods (solvers/coloring.hpp): on a tet scene and a cloth,
// no two vertices of one colour share an element, every free vertex is coloured once, pinned ones
// never, and the colouring is the same every time (the order of a deterministic sweep).
#include "problems/scene.hpp"
#include "solvers/coloring.hpp"
#include "solvers/local/vbd.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace xb;

namespace {

void check_coloring(const Problem& prob) {
  const Coloring c = free_vertex_coloring(prob);
  const int n = prob.particles.size();
  ASSERT_EQ(static_cast<int>(c.color.size()), n);
  std::vector<int> seen(n, 0);
  for (int k = 0; k < c.num_colors; ++k)
    for (int q = c.color_start[k]; q < c.color_start[k + 1]; ++q) {
      const int v = c.order[q];
      EXPECT_EQ(c.color[v], k);
      ++seen[v];
    }
  int free = 0;
  for (int v = 0; v < n; ++v) {
    const bool active = prob.particles.w[v] > 0;
    free += active;
    EXPECT_EQ(seen[v], active ? 1 : 0) << "vertex " << v;
    if (!active) {
      EXPECT_EQ(c.color[v], -1);
    }
  }
  EXPECT_EQ(static_cast<int>(c.order.size()), free);
  for (int j = 0; j < prob.num_constraints(); ++j) {
    std::set<int> colours;
    int members = 0;
    for (int v : prob.constraint_particles(j))
      if (v >= 0 && prob.particles.w[v] > 0) {
        colours.insert(c.color[v]);
        ++members;
      }
    EXPECT_EQ(static_cast<int>(colours.size()), members) << "constraint " << j << " has two vertices of one colour";
  }
  const Coloring again = free_vertex_coloring(prob);
  EXPECT_EQ(again.order, c.order);
}

}  // namespace

TEST(VertexColoring, NoElementHoldsTwoVerticesOfOneColour) {
  SceneSettings tets;
  tets.scene = "squash";
  tets.resolution = 6;
  check_coloring(build_problem(tets));
  SceneSettings cloth;
  cloth.scene = "cloth_hang";
  cloth.resolution = 8;  // two corners pinned
  check_coloring(build_problem(cloth));
}

TEST(VertexColoring, PinnedVerticesDoNotConflict) {
  // A path 0–1–2 with 1 pinned: 0 and 2 share no element with a free vertex between them.
  const std::vector<std::array<int, 4>> elements = {{0, 1, -1, -1}, {1, 2, -1, -1}};
  const Coloring c = element_vertex_coloring(3, elements, {1, 0, 1});
  EXPECT_EQ(c.num_colors, 1);
  EXPECT_EQ(c.color[1], -1);
  EXPECT_EQ(c.order, (std::vector<int>{0, 2}));
}
