#include "key_scope.hpp"

#include "error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace xb {

namespace {
std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

// "a||b" → a, "", b: a condition may name the empty value ("mesh=|bar": no mesh, or bar).
std::vector<std::string> split_keep(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (char c : s) {
    if (c == sep) out.emplace_back();
    else out.back() += c;
  }
  return out;
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

bool contains(const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); }

// Text that is a whole number → true and its value.
bool number(const std::string& text, double& v) {
  char* end = nullptr;
  v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(v);
}

// Numbers compare as numbers ("1e-08" = "1e-8"), everything else as text.
bool same_value(const std::string& a, const std::string& b) {
  double x = 0, y = 0;
  if (number(a, x) && number(b, y)) return x == y;
  return a == b;
}

bool holds(const Condition& c, const std::string& value) {
  const bool listed = std::any_of(c.values.begin(), c.values.end(), [&](const std::string& v) { return same_value(v, value); });
  if (c.op == "=") return listed;
  if (c.op == "!=") return !listed;
  double x = 0, bound = 0;
  if (!number(value, x) || !number(c.values[0], bound)) return false;
  return c.op == ">" ? x > bound : x < bound;
}

std::string method_words(const std::string& m) {
  if (m == "local") return "the local methods";
  if (m == "global") return "every global method";
  if (m == "python") return "py:<name> solvers";
  return m;
}
}  // namespace

Condition parse_condition(const std::string& text) {
  for (const char* op : {"!=", "=", ">", "<"}) {
    const auto at = text.find(op);
    if (at == std::string::npos || at == 0) continue;
    Condition c{text.substr(0, at), op, split_keep(text.substr(at + std::string(op).size()), '|')};
    if ((c.op == ">" || c.op == "<") && (c.values.size() != 1 || c.values[0].empty())) break;
    return c;
  }
  throw Error("malformed scope condition '" + text + "' (key=a|b, key!=a|b, key>x or key<x)");
}

Scope Scope::in(const std::string& form) && {
  forms.push_back(form);
  return std::move(*this);
}
Scope Scope::where(const std::string& condition) && {
  when.push_back(condition);
  return std::move(*this);
}
Scope Scope::with_reference() && {
  reference = true;
  return std::move(*this);
}
Scope Scope::also_solve() && {
  solve = true;
  return std::move(*this);
}

Scope on(const std::string& methods) { return Scope{split(methods, ','), {}, {}, false, false}; }

bool in_scope(const Scope& s, const RunSite& site) {
  if (site.solve && !s.solve) return false;
  const bool known = !site.method.empty();
  if (known && !s.methods.empty()) {
    const bool match = std::any_of(s.methods.begin(), s.methods.end(), [&](const std::string& m) {
      return m == site.method || (m == "local" && site.local) || (m == "global" && !site.local) || (m == "python" && site.python);
    });
    if (!match) return false;
  }
  if (!s.forms.empty()) {
    if (known && site.local) return false;
    if (!site.form.empty() && !contains(s.forms, site.form)) return false;
  }
  if (s.reference && site.reference == false) return false;
  for (const auto& text : s.when) {
    const Condition c = parse_condition(text);
    const std::optional<std::string> v = site.value ? site.value(c.key) : std::nullopt;
    if (v && !holds(c, *v)) return false;
  }
  return true;
}

bool has_effect(const KeyScope& k, const RunSite& site) {
  if (k.kind == KeyScope::Kind::record) return true;
  return std::any_of(k.any.begin(), k.any.end(), [&](const Scope& s) { return in_scope(s, site); });
}

std::string describe(const Scope& s) {
  std::vector<std::string> methods;
  for (const auto& m : s.methods) methods.push_back(method_words(m));
  std::string out = methods.empty() ? "every run" : join(methods, ", ");
  if (!s.forms.empty()) out += " in the " + join(s.forms, " or ") + " form";
  std::vector<std::string> when;
  for (const auto& text : s.when) {
    const Condition c = parse_condition(text);
    std::vector<std::string> values;
    for (const auto& v : c.values) values.push_back(v.empty() ? "''" : v);
    when.push_back(c.key + " " + c.op + " " + join(values, " | "));
  }
  if (!when.empty()) out += " with " + join(when, " and ");
  if (s.reference) out += " with --reference";
  return out;
}

std::string describe(const KeyScope& k) {
  if (k.kind == KeyScope::Kind::undeclared) return "undeclared";
  if (k.kind == KeyScope::Kind::record) return "recorded only: " + k.record;
  std::vector<std::string> parts;
  for (const auto& s : k.any) parts.push_back(describe(s));
  std::string out = join(parts, "; ");
  for (const auto& [where, key] : k.instead) out += "; " + describe(where) + " reads " + key + " instead";
  return out;
}

std::string describe(const RunSite& site) {
  if (site.method.empty()) {
    const auto scene = site.value ? site.value("scene") : std::nullopt;
    return scene ? "any run of scene '" + *scene + "'" : "any run";
  }
  std::string out = site.method + (site.local ? " (a local method)" : "");
  if (!site.form.empty()) out += ", " + site.form + " form";
  if (site.solve) out += ", one solve of a captured system";
  return out;
}

std::string scope_refusal(const std::string& key, const KeyScope& k, const std::vector<RunSite>& runs) {
  if (k.kind == KeyScope::Kind::undeclared) throw Error("parameter '" + key + "' declares no scope (where it has an effect)");
  if (runs.empty() || std::any_of(runs.begin(), runs.end(), [&](const RunSite& r) { return has_effect(k, r); })) return "";
  std::vector<std::string> sites;
  for (const auto& r : runs)
    if (!contains(sites, describe(r))) sites.push_back(describe(r));
  if (sites.size() > 3) sites.resize(3), sites.push_back("...");
  const std::string in = runs.size() == 1 && runs[0].method.empty() ? describe(runs[0])
                         : (runs.size() == 1 ? "this run (" : "any run here (") + join(sites, "; ") + ")";
  std::string msg = "parameter '" + key + "' has no effect in " + in + ": it applies to " + describe(KeyScope{k.kind, k.any, {}, ""});
  for (RunSite r : runs) {
    r.solve = false;  // the key named instead is the one for such runs, in `run` or in `solve`
    for (const auto& [where, other] : k.instead)
      if (in_scope(where, r)) return msg + "; here the key that applies is '" + other + "'";
  }
  return msg;
}

}  // namespace xb
