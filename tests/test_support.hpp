// What the tests of the CLI level share: MPI started once (the harness is an MPI program), one
// OpenMP thread, a temporary directory per test, and typed access to a run's attributes.
#pragma once

#include "harness/io/recorder.hpp"

#include <gtest/gtest.h>
#include <mpi.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

namespace xb::test {

// The harness is an MPI program (hypre, muelu; parse_methods asks for the communicator size), so
// in-process commands need MPI initialised, as xpbd-bench's main does. Only tests that call
// ensure_mpi() start it (on first use), so other tests do not pay for MPI's start-up.
inline bool mpi_started_here = false;
inline void ensure_mpi() {
  int done = 0;
  MPI_Initialized(&done);
  if (!done) mpi_started_here = MPI_Init(nullptr, nullptr) == MPI_SUCCESS;
}
class MpiEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    int done = 0;
    MPI_Finalized(&done);
    if (mpi_started_here && !done) MPI_Finalize();
  }
};
[[maybe_unused]] inline ::testing::Environment* const mpi_env = ::testing::AddGlobalTestEnvironment(new MpiEnvironment);

// Every test here runs on one OpenMP thread (restored afterwards): what they check (iteration
// counts, residuals, bit-exact files) does not depend on the thread count, and on a machine
// shared by many builds two spinning threads are many times slower than one.
struct OneThread {
  int saved = omp_get_max_threads();
  OneThread() { omp_set_num_threads(1); }
  ~OneThread() { omp_set_num_threads(saved); }
};

struct TempDir {
  OneThread one_thread;
  std::filesystem::path path;
  TempDir() {
    ensure_mpi();
    path = std::filesystem::temp_directory_path() / ("xb_linear_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
};


inline double attr_double(const RunRecord& r, const std::string& k) {
  auto it = r.attrs.find(k);
  if (it == r.attrs.end()) ADD_FAILURE() << r.name << ": no attribute " << k;
  if (it == r.attrs.end()) return NAN;
  if (auto* d = std::get_if<double>(&it->second)) return *d;
  if (auto* i = std::get_if<long long>(&it->second)) return static_cast<double>(*i);
  ADD_FAILURE() << r.name << ": attribute " << k << " is a string";
  return NAN;
}

inline std::string attr_string(const RunRecord& r, const std::string& k) {
  auto it = r.attrs.find(k);
  if (it == r.attrs.end()) return "<missing>";
  if (auto* s = std::get_if<std::string>(&it->second)) return *s;
  return "<not a string>";
}

inline const RunRecord& run_of(const std::vector<RunRecord>& runs, const std::string& solver) {
  for (const auto& r : runs)
    if (attr_string(r, "solver") == solver) return r;
  throw std::runtime_error("no run of " + solver);
}

}  // namespace xb::test
