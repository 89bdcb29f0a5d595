// The smoother interface (smoother.hpp): a polynomial smoother refuses a matrix without a positive
// λ_max estimate, and only the polynomial kinds take a shared λ_max.
#include "solvers/amg/relaxation/smoothers.hpp"
#include "core/error.hpp"

#include "../amg_test_support.hpp"

#include <gtest/gtest.h>

using namespace xb;
using namespace xb::amg;
using namespace xb::test;

TEST(Smoother, PolynomialKindsRefuseANegativeDefiniteMatrix) {
  const SparseMatrix A = -poisson2d(6);
  SmootherOptions o;
  for (const std::string kind : {"jacobi", "chebyshev"}) {
    o.kind = kind;
    EXPECT_THROW(make_smoother(o, A), Error) << kind;
  }
}

TEST(Smoother, OnlyPolynomialKindsTakeASharedLambdaMax) {
  const SparseMatrix A = poisson2d(6);
  SmootherOptions o;
  o.kind = "jacobi";
  auto jacobi = make_smoother(o, A);
  jacobi->set_lambda_max(3.5);
  EXPECT_EQ(jacobi->lambda_max(), 3.5);
  o.kind = "gs";
  EXPECT_THROW(make_smoother(o, A)->set_lambda_max(3.5), Error);
}
