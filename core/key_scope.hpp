// Where a setting has an effect. Every key of the flat key space declares in its table row the
// runs that read it (its KeyScope), so that a key set where nothing reads it is refused, naming the
// key that does that job there, instead of silently changing nothing (harness/key_check.hpp).
//
//   setting("amg.strength_threshold", ...)
//       .applies({on("mgpbd").in("dual"), on("hypre,muelu")})
//       .instead(on("mgpbd").in("primal"), "amg.nodal_strength_threshold")
//
// A run is seen as a RunSite: its method, its resolved form, whether it has a reference, and the
// value of every key (conditions such as "step=fixed" read them).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace xb {

// One set of runs: all of its conditions hold.
struct Scope {
  std::vector<std::string> methods;  // names, or local | global | python (py:<name> solvers); empty = every method
  std::vector<std::string> forms;    // dual | primal (so global methods only); empty = any
  std::vector<std::string> when;     // conditions on the run's keys: "key=a|b", "key!=a|b", "key>x", "key<x"
  bool reference = false;            // only runs with --reference
  bool solve = false;                // also `solve` runs (one linear solve of a captured system)

  Scope in(const std::string& form) &&;          // and the linear step in this form
  Scope where(const std::string& condition) &&;  // and this condition on a key
  Scope with_reference() &&;
  Scope also_solve() &&;
};
// The runs of these methods (comma-separated; "" = every method).
Scope on(const std::string& methods);

struct KeyScope {
  enum class Kind { undeclared, effect, record };
  Kind kind = Kind::undeclared;
  std::vector<Scope> any;  // effect: the key changes a run where one of these holds
  std::vector<std::pair<Scope, std::string>> instead;  // where it does not: the key that does its job there
  std::string record;  // record: what it does without changing a result (threads: the results do not depend on them)
};

// A run as the scopes see it. An unknown part (an empty method, no reference flag, a key whose
// value is nullopt) matches any scope: a site with only the scene known stands for every run of it.
struct RunSite {
  std::string method;  // "" = unknown
  bool local = false, python = false;
  std::string form;  // dual | primal for a global method; "" for a local one or unknown
  std::optional<bool> reference;
  bool solve = false;  // a `solve` run
  std::function<std::optional<std::string>(const std::string& key)> value;
};

bool in_scope(const Scope& s, const RunSite& site);
bool has_effect(const KeyScope& k, const RunSite& site);

// In words, for messages and `list`: "mgpbd in the dual form", "every global method with step = fixed".
std::string describe(const Scope& s);
std::string describe(const KeyScope& k);
std::string describe(const RunSite& site);  // "mgpbd, primal form"

// "" when `key` has an effect in one of `runs` (or is a record setting); else why not, in one
// sentence naming the key that does its job in the first run where one is declared.
std::string scope_refusal(const std::string& key, const KeyScope& k, const std::vector<RunSite>& runs);

// A condition taken apart: "a.b!=x|y" → {"a.b", "!=", {"x", "y"}}. Throws xb::Error when malformed.
struct Condition {
  std::string key, op;
  std::vector<std::string> values;
};
Condition parse_condition(const std::string& text);

}  // namespace xb
