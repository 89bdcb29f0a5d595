#include "core/reduce.hpp"

#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace {

std::vector<double> random_terms(long n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (auto& x : v) x = u(rng) * std::exp(20 * u(rng));  // many magnitudes: every order rounds differently
  return v;
}

// The definition: chunk sums in index order, added in chunk order.
double chunked_by_hand(const std::vector<double>& v) {
  double total = 0;
  for (long lo = 0; lo < static_cast<long>(v.size()); lo += xb::reduce_chunk) {
    double s = 0;
    for (long i = lo; i < std::min<long>(v.size(), lo + xb::reduce_chunk); ++i) s += v[i];
    total += s;
  }
  return total;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(DeterministicSum, SameBitsForAnyThreadCountAndEqualToItsDefinition) {
  for (long n : {0L, 1L, 1023L, 1024L, 1025L, 4097L, 100000L, 270199L}) {
    const std::vector<double> v = random_terms(n);
    const double expected = chunked_by_hand(v);
    const int saved = omp_get_max_threads();
    for (int t : {1, 2, 3, 4, 7}) {
      omp_set_num_threads(t);
      const double s = xb::deterministic_sum(n, [&](long i) { return v[i]; });
      EXPECT_TRUE(same_bits(s, expected)) << "n = " << n << ", threads = " << t << ": " << s << " vs " << expected;
    }
    omp_set_num_threads(saved);
  }
}

TEST(DeterministicSum, SeveralSumsInOnePass) {
  const std::vector<double> v = random_terms(50000);
  std::vector<double> sq(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) sq[i] = v[i] * v[i];
  const auto two = xb::deterministic_sums<2>(static_cast<long>(v.size()), [&](long lo, long hi, double* acc) {
    for (long i = lo; i < hi; ++i) acc[0] += v[i], acc[1] += v[i] * v[i];
  });
  EXPECT_TRUE(same_bits(two[0], chunked_by_hand(v)));
  EXPECT_TRUE(same_bits(two[1], chunked_by_hand(sq)));
}

TEST(DeterministicSum, BlocksOfAnotherMeasureCutOnChunkBoundaries) {
  // Thread blocks that start anywhere (here: skewed towards the end, as SpMV's blocks of equal
  // non-zeros are on rows that grow): each chunk is still summed whole, so the sums are the
  // definition's for any thread count, and every index is visited once.
  const long n = 50000;
  const std::vector<double> v = random_terms(n);
  auto skewed = [&](int t, int T) { return static_cast<long>(n * std::sqrt(static_cast<double>(t) / T)); };
  const int saved = omp_get_max_threads();
  for (int t : {1, 2, 3, 4, 7, 16}) {
    omp_set_num_threads(t);
    std::vector<int> visits(n, 0);
    const auto s = xb::deterministic_sums_in_blocks<1>(n, skewed, [&](long lo, long hi, double* acc) {
      for (long i = lo; i < hi; ++i) acc[0] += v[i], ++visits[i];
    });
    EXPECT_TRUE(same_bits(s[0], chunked_by_hand(v))) << t << " threads";
    EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), n) << t << " threads";
  }
  omp_set_num_threads(saved);
}

}  // namespace
