// take(): the destination gets the source's arrays, not a copy of them (Eigen 3.4's SparseMatrix
// copies on std::move and on assignment from a returned matrix).
#include "core/sparse.hpp"

#include <gtest/gtest.h>

using namespace xb;

namespace {
SparseMatrix identity(int n) {
  SparseMatrix m(n, n);
  m.setIdentity();
  return m;
}
}  // namespace

TEST(Sparse, TakeMovesTheArrays) {
  SparseMatrix src = identity(1000), dst = identity(3);
  const double* values = src.valuePtr();
  const int* columns = src.innerIndexPtr();
  take(dst, std::move(src));
  EXPECT_EQ(dst.valuePtr(), values);
  EXPECT_EQ(dst.innerIndexPtr(), columns);
  EXPECT_EQ(dst.rows(), 1000);
  EXPECT_EQ(dst.nonZeros(), 1000);
  take(dst, identity(7));  // a returned matrix
  EXPECT_EQ(dst.rows(), 7);
  EXPECT_EQ(dst.nonZeros(), 7);
  // What take() is for: plain assignment copies.
  SparseMatrix copy;
  copy = dst;
  EXPECT_NE(copy.valuePtr(), dst.valuePtr());
}
