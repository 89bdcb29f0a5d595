// The smoother kinds (smoothers.hpp): every name in kSmootherKinds makes the smoother of that name;
// an unknown name and bad counts are refused.
#include "solvers/amg/relaxation/smoothers.hpp"
#include "core/error.hpp"

#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(Smoothers, EveryKindMakesTheSmootherOfItsName) {
  const SparseMatrix A = poisson2d(6);
  int made = 0;
  for (const std::string& kind : smoother_kinds()) {
    SmootherOptions o;
    o.kind = kind;
    EXPECT_EQ(make_smoother(o, A)->name(), kind);
    ++made;
  }
  EXPECT_EQ(made, 6);
}

TEST(Smoothers, UnknownKindAndBadCountsAreRefused) {
  const SparseMatrix A = poisson2d(4);
  SmootherOptions o;
  o.kind = "sor";
  EXPECT_THROW(make_smoother(o, A), Error);
  o = SmootherOptions();
  o.sweeps = 0;
  EXPECT_THROW(make_smoother(o, A), Error);
  o = SmootherOptions();
  o.degree = 0;
  EXPECT_THROW(make_smoother(o, A), Error);
}
