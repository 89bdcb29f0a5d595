// What tests/harness/test_key_effects.cpp runs: the kinds of run a key is tried in, the values it
// is tried at, and what a run is compared by.
#pragma once

#include "harness/params.hpp"

#include <map>
#include <string>
#include <vector>

namespace xb::test {

// Everything a run computes that does not depend on the clock.
struct Outcome {
  bool error = false;  // the run refused (an xb::Error, or status error)
  std::string message;
  std::string status, reference_method;
  long long outer_iterations = 0;
  std::vector<double> x, logged;
  std::vector<long long> counts;
  std::map<std::string, double> stats;
  bool operator==(const Outcome& o) const {
    return error == o.error && status == o.status && reference_method == o.reference_method &&
           outer_iterations == o.outer_iterations && x == o.x && logged == o.logged && counts == o.counts && stats == o.stats;
  }
};
Outcome run_outcome(const Params& p, const std::string& method, bool reference);

// One kind of run: base parameters (a tiny stock scene), a method, whether it has a reference.
struct Context {
  std::string name;
  Params params;
  std::string method;
  bool reference = false;
};
// The runs a key is tried in: every stock scene for a scene key; otherwise every method (each
// global one in both forms, under the fixed step, the line search and Newton's profile) on a
// small twisted bar; and those runs again with each clause of its scope made true.
std::vector<Context> contexts_for(const ParamField& f);
// The values a key is tried at besides the one in p: every other choice, or numbers around it.
std::vector<std::string> probe_values(const ParamField& f, const Params& p);

// py:test, a registered method that reads only its tolerance, as the Python solvers do.
void register_test_solver();

}  // namespace xb::test
