// Strength of connection (strength.hpp) against the rule applied by hand.
#include "core/error.hpp"
#include "solvers/amg/strength.hpp"

#include "amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;
using Dense = Eigen::MatrixXd;

TEST(AmgStrength, KeepsExactlyTheStrongEntries) {
  SceneSystem s = scene_system("cloth_hang", 6, 0);
  const SparseMatrix& A = s.ds->A();
  const Eigen::MatrixXd D(A);
  for (double theta : {0.0, 0.1, 0.25, 0.5}) {
    const Eigen::MatrixXd S(strength_symmetric(A, theta));
    long expected = 0;
    for (int k = 0; k < A.outerSize(); ++k)
      for (SparseMatrix::InnerIterator it(A, k); it; ++it) {
        const int i = it.row(), j = it.col();
        const bool strong = i == j || std::abs(it.value()) >= theta * std::sqrt(std::abs(D(i, i) * D(j, j)));
        expected += strong;
        EXPECT_EQ(S(i, j), strong ? it.value() : 0.0);
      }
    EXPECT_EQ(strength_symmetric(A, theta).nonZeros(), expected) << theta;
    if (theta == 0) {
      EXPECT_EQ(expected, A.nonZeros());
    }
  }
  EXPECT_THROW(strength_symmetric(A, -1), Error);
}
