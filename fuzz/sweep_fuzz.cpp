// Sweep spec reader: the spec at its default size and at size "paper", then its expansion into
// jobs (every job's parameters resolved and checked). The spec's scene may name a built-in scene
// or a file beside the spec, which is not there: that ends in the error for a missing scene.
#include "fuzz_input.hpp"

#include "harness/cli/sweep.hpp"

namespace {
// Expanding allocates one job per grid point × solver × repeat: a spec of a billion jobs is
// valid text but no reading question, so only specs of at most this many jobs are expanded.
constexpr double max_expanded_jobs = 4096;

void read_spec(const std::string& path, const std::string& size) {
  const xb::SweepSpec spec = xb::parse_sweep_spec(path, size);
  double jobs = static_cast<double>(spec.solvers.size()) * spec.repeats;
  for (const auto& axis : spec.grid) jobs *= static_cast<double>(axis.second.size());
  if (jobs <= max_expanded_jobs) {
    xb::expand_sweep(spec);
    xb::sweep_base_hash(spec);
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = xb_fuzz::write_file("spec.toml", xb_fuzz::as_text(data, size));
  xb_fuzz::expect_clean([&] { read_spec(path, "default"); });
  xb_fuzz::expect_clean([&] { read_spec(path, "paper"); });
  return 0;
}
