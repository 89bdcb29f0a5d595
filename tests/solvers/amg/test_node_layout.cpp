// Node layouts (node_layout.hpp): uniform blocks cover the rows, a scalar layout is empty.
#include "solvers/amg/node_layout.hpp"
#include "core/error.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;

TEST(NodeLayout, UniformBlocksCoverTheRows) {
  const NodeLayout l = NodeLayout::uniform(12, 3);
  EXPECT_FALSE(l.scalar());
  EXPECT_EQ(l.num_nodes(), 4);
  EXPECT_EQ(l.node_start, (std::vector<int>{0, 3, 6, 9, 12}));
  EXPECT_TRUE(NodeLayout{}.scalar());
}

TEST(NodeLayout, ABlockSizeThatDoesNotDivideTheRowsIsRefused) {
  EXPECT_THROW(NodeLayout::uniform(10, 3), Error);
  EXPECT_THROW(NodeLayout::uniform(9, 0), Error);
}
