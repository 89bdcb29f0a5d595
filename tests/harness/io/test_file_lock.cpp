// The shared counter by which mpirun's ranks take a sweep's jobs (harness/io/file_lock.hpp): every
// number once across its users, and a counter file nobody holds is known stale.
#include "harness/io/file_lock.hpp"

#include "test_support.hpp"

#include <algorithm>
#include <thread>

namespace fs = std::filesystem;
using namespace xb;
using xb::test::TempDir;

TEST(SharedCounter, EveryNumberGoesToOneUserOnly) {
  TempDir d;
  const std::string path = d / "runs/queue-0";
  std::vector<std::vector<long>> taken(4);
  std::vector<std::thread> users;
  for (int u = 0; u < 4; ++u)
    users.emplace_back([&, u] {
      SharedCounter c(path);  // one open file each: they exclude each other as processes do
      for (long n = c.next(); n < 20000; n = c.next()) taken[u].push_back(n);
    });
  for (auto& t : users) t.join();
  std::vector<long> all;
  for (const auto& t : taken) all.insert(all.end(), t.begin(), t.end());
  std::sort(all.begin(), all.end());
  ASSERT_EQ(all.size(), 20000u);
  for (long i = 0; i < 20000; ++i) ASSERT_EQ(all[i], i);
}

TEST(SharedCounter, OnlyACounterNobodyHoldsIsRemoved) {
  TempDir d;
  const std::string path = d / "queue-1";
  {
    SharedCounter held(path);
    EXPECT_EQ(held.next(), 0);
    EXPECT_FALSE(remove_unused_counter(path));
    EXPECT_TRUE(fs::exists(path));
    EXPECT_EQ(held.next(), 1);
  }
  EXPECT_TRUE(remove_unused_counter(path));
  EXPECT_FALSE(fs::exists(path));
}
