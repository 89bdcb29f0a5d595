// Stored references (harness/sim/reference_store.hpp, `run --reference-file`): a reference is
// computed once and read back bit for bit by every run of the same problem and predicted state;
// another problem is refused naming what differs, another state is computed afresh, never reused;
// every field of ReferenceSolution makes the round trip; and the run's limits (over_budget,
// out_of_memory) end it with its log kept.
#include "sim_test_support.hpp"

#include "harness/io/reference_file.hpp"
#include "harness/sim/reference_store.hpp"
#include "harness/sim/simulation.hpp"
#include "problems/scene.hpp"
#include "problems/dual_system.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <type_traits>
#include <variant>

namespace fs = std::filesystem;

namespace xb {
namespace {

using test::newton_params;

struct TempDir {
  fs::path dir = fs::temp_directory_path() / ("xb_reference_store_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(dir); }
  ~TempDir() { fs::remove_all(dir); }
  std::string file(const std::string& name) const { return (dir / name).string(); }
};

Params small_squash() {
  Params p = newton_params("squash");
  p.resolution = 5;
  return p;
}

RunResult run_with_store(const Params& p, const std::string& method, const std::string& file) {
  RunOptions opt;
  opt.reference = true;
  opt.reference_file = file;
  return run_simulation(build_problem(p), p, method, opt);
}

// The first run computes and stores the reference; a second run of another method reads it: the
// same reference, so the same position error at its x̃ and an error series that reaches 0 where
// the Newton run does; the file holds one reference.
TEST(ReferenceStore, ComputedOnceAndReadByTheNextRun) {
  TempDir t;
  const Params p = small_squash();
  const std::string file = t.file("squash.ref.h5");
  const RunResult first = run_with_store(p, "cholmod", file);
  ASSERT_EQ(first.status, "ok") << first.message;
  ASSERT_EQ(first.log.reference_source, std::vector<std::string>{"stored"});
  const RunResult second = run_with_store(p, "cholmod", file);
  ASSERT_EQ(second.log.reference_source, std::vector<std::string>{"read"});
  EXPECT_EQ(second.log.position_error, first.log.position_error);  // bit for bit: the same x_ref
  EXPECT_EQ(second.log.reference_status, first.log.reference_status);
  EXPECT_EQ(second.log.reference_relative_energy_gradient, first.log.reference_relative_energy_gradient);
  // The certificate travels with the stored reference.
  EXPECT_EQ(second.log.reference_certified, first.log.reference_certified);
  EXPECT_EQ(second.log.reference_error_estimate, first.log.reference_error_estimate);
  EXPECT_EQ(second.log.reference_error_scale, first.log.reference_error_scale);
  EXPECT_EQ(second.log.reference_certificate_note, first.log.reference_certificate_note);
  EXPECT_EQ(second.reference_method, first.reference_method);
  const RunResult other = run_with_store(p, "mgpbd", file);
  ASSERT_EQ(other.log.reference_source, std::vector<std::string>{"read"});
  EXPECT_EQ(other.log.position_error.front(), first.log.position_error.front());
  // Without a store the reference is the same computation.
  RunOptions plain;
  plain.reference = true;
  const RunResult fresh = run_simulation(build_problem(p), p, "cholmod", plain);
  EXPECT_EQ(fresh.log.position_error, first.log.position_error);
  EXPECT_TRUE(fresh.log.reference_source.empty());
}

// Every field of reference_fields makes the round trip with a value that is not its default.
TEST(ReferenceStore, EveryFieldRoundTrips) {
  TempDir t;
  const Params p = small_squash();
  const Problem prob = build_problem(p);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt / p.substeps);
  ReferenceStore store(t.file("fields.ref.h5"), p, prob, at);
  ReferenceSolution r;
  r.x = Eigen::Matrix3Xd::Random(3, prob.particles.size());
  int k = 0;
  for (const ReferenceField& f : reference_fields)
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(r.*member)>;
          ++k;
          if constexpr (std::is_same_v<T, std::string>) r.*member = "value " + std::to_string(k);
          else if constexpr (std::is_same_v<T, bool>) r.*member = true;
          else if constexpr (std::is_same_v<T, StopReason>) r.*member = StopReason::line_search_at_floor;
          else r.*member = static_cast<T>(1000 + k * 7.25);
        },
        f.member);
  const Eigen::Matrix3Xd x_pred = prob.particles.x;
  ASSERT_TRUE(store.store(0, 0, x_pred, r, 1.5));
  const std::optional<ReferenceSolution> back = store.find(0, 0, x_pred);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->x, r.x);
  for (const ReferenceField& f : reference_fields)
    std::visit([&](auto member) { EXPECT_EQ((*back).*member, r.*member) << f.name; }, f.member);
  EXPECT_FALSE(store.find(0, 1, x_pred));  // no other substep
  EXPECT_FALSE(store.find(1, 0, x_pred));
}

// A file of another problem (here: another stiffness) is refused, naming the key; the same problem
// from another predicted state is not read (and not stored over the first).
TEST(ReferenceStore, AnotherProblemOrStateIsNeverReused) {
  TempDir t;
  const std::string file = t.file("squash.ref.h5");
  Params p = small_squash();
  const Problem prob = build_problem(p);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt / p.substeps);
  ReferenceStore store(file, p, prob, at);
  ReferenceSolution r;
  r.x = prob.particles.x;
  r.status = StopReason::converged;
  Eigen::Matrix3Xd x_pred = prob.particles.x;
  ASSERT_TRUE(store.store(0, 0, x_pred, r, 0.1));
  x_pred(1, 0) += 1e-15;  // one bit of one coordinate
  EXPECT_FALSE(store.find(0, 0, x_pred));
  EXPECT_FALSE(store.store(0, 0, x_pred, r, 0.1));
  x_pred(1, 0) -= 1e-15;
  EXPECT_TRUE(store.find(0, 0, prob.particles.x));
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"stiffness", "2e6"}, {"dt", "0.004"}, {"init", "enlarge"}, {"reference.linear", "mgpbd"}}) {
    Params q = p;
    set_param(q, key, value, "test");
    const Problem other = build_problem(q);
    const Eigen::VectorXd at_q = scaled_compliance(other, q.dt / q.substeps);
    try {
      ReferenceStore s(file, q, other, at_q);
      ADD_FAILURE() << key << ": a file of another problem was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("this run: " + key + " = "), std::string::npos) << e.what();
    }
  }
  Params frames = p;  // the frame count is not the problem
  frames.frames = 3;
  EXPECT_NO_THROW(ReferenceStore(file, frames, prob, at));
}

// A stored reference without one of the fields (an older file) is refused, not read with a default.
TEST(ReferenceStore, AStoredReferenceLackingAFieldIsRefused) {
  TempDir t;
  const std::string file = t.file("old.ref.h5");
  const Params p = small_squash();
  const Problem prob = build_problem(p);
  const Eigen::VectorXd at = scaled_compliance(prob, p.dt / p.substeps);
  ReferenceFileHeader h;
  h.problem = reference_problem(p, prob, at);
  h.problem_hash = hash_hex(h.problem.data(), h.problem.size());
  h.particles = prob.particles.size();
  StoredReference s;
  s.state_hash = hash_hex(prob.particles.x.data(), sizeof(double) * prob.particles.x.size());
  s.x = prob.particles.x;
  s.fields["status"] = std::string("converged");  // the others missing
  ASSERT_TRUE(add_reference(file, h, s));
  ReferenceStore store(file, p, prob, at);
  EXPECT_THROW(store.find(0, 0, prob.particles.x), Error);
}

// A resident set past the memory limit ends the run as out_of_memory before its first step, its
// log kept; a time budget of (almost) nothing ends it as over_budget.
TEST(RunLimits, MemoryAndTimeEndTheRunWithTheirOwnStatus) {
  const Params p = small_squash();
  RunOptions opt;
  opt.reference = true;
  opt.memory_limit = 1e6;  // 1 MB: any process is past it
  const RunResult oom = run_simulation(build_problem(p), p, "mgpbd", opt);
  EXPECT_EQ(oom.status, "out_of_memory");
  EXPECT_NE(oom.message.find("over the memory limit of 0.00 GB"), std::string::npos) << oom.message;
  ASSERT_EQ(oom.log.position_error.size(), 1u);  // iteration 0 is logged, with its error
  EXPECT_GT(oom.stats.at("peak_memory"), 1e6);
  RunOptions slow;
  slow.time_budget = 1e-9;
  const RunResult late = run_simulation(build_problem(p), p, "mgpbd", slow);
  EXPECT_EQ(late.status, "over_budget");
  EXPECT_NE(late.message.find("time budget"), std::string::npos);
}

}  // namespace
}  // namespace xb
