// The typed settings table every component uses for its keys. A component (the scene, the
// stepper, each solver) owns a plain settings struct and one table of its keys — key, doc, bounds,
// choices, member — next to the code that reads them; the harness composes the tables into the one
// flat key space of scene files, --set and the HDF5 run attributes (harness/params.hpp).
#pragma once

#include "key_scope.hpp"

#include <functional>
#include <string>
#include <variant>
#include <vector>

namespace xb {

enum class SettingType { Int, Double, String };
using SettingRef = std::variant<int*, double*, std::string*>;
using SettingValue = std::variant<long long, double, std::string>;

// One key of settings struct S.
template <class S>
struct SettingField {
  std::string key;  // as users write it, e.g. "amg.strength_threshold"
  SettingType type;
  std::string doc;  // one line, with units
  std::function<SettingRef(S&)> ref;  // the member it sets, in a given S
  double min = -1e300, max = 1e300;   // inclusive bounds for numbers
  std::vector<std::string> choices;   // allowed strings, empty = any
  KeyScope scope;                     // where it has an effect (core/key_scope.hpp)
  bool list = false;                  // a string that files may write as a TOML list (joined with ", ")

  // The row's scope, declared beside its doc: the runs it changes, the key that does its job
  // where it does not, or a setting that is only recorded.
  SettingField applies(std::vector<Scope> where) && {
    scope.kind = KeyScope::Kind::effect;
    scope.any = std::move(where);
    return std::move(*this);
  }
  SettingField instead(Scope where, std::string key) && {
    scope.instead.emplace_back(std::move(where), std::move(key));
    return std::move(*this);
  }
  SettingField record_only(std::string why) && {
    scope.kind = KeyScope::Kind::record;
    scope.record = std::move(why);
    return std::move(*this);
  }
  SettingField list_value() && {
    list = true;
    return std::move(*this);
  }
};
template <class S>
using SettingTable = std::vector<SettingField<S>>;

namespace detail {
template <class T>
constexpr SettingType setting_type() {
  if constexpr (std::is_same_v<T, int>) return SettingType::Int;
  else if constexpr (std::is_same_v<T, double>) return SettingType::Double;
  else return SettingType::String;
}
}  // namespace detail

// A table row for member `m` of S (the type follows the member's).
template <class S, class T>
SettingField<S> setting(std::string key, std::string doc, T S::*m, double min = -1e300, double max = 1e300,
                        std::vector<std::string> choices = {}) {
  return {std::move(key), detail::setting_type<T>(), std::move(doc), [m](S& s) { return SettingRef(&(s.*m)); },
          min, max, std::move(choices)};
}
template <class S>
SettingField<S> setting(std::string key, std::string doc, std::string S::*m, std::vector<std::string> choices) {
  return setting(std::move(key), std::move(doc), m, 0, 0, std::move(choices));
}

// A part's row as a row of its owner's table: `part` maps an Outer to its Inner.
template <class Outer, class Inner, class Part>
SettingField<Outer> rebind(const SettingField<Inner>& f, Part part) {
  SettingField<Outer> o{f.key, f.type, f.doc, [r = f.ref, part](Outer& x) { return r(part(x)); }, f.min, f.max, f.choices};
  o.scope = f.scope;
  o.list = f.list;
  return o;
}
// Appends the rows of a part's table to its owner's.
template <class Outer, class Inner, class Part>
void append_part(SettingTable<Outer>& out, const SettingTable<Inner>& in, Part part) {
  for (const auto& f : in) out.push_back(rebind<Outer>(f, part));
}

// Text → a finite double. Returns "" when `v` was set, else what is wrong, in the words every
// error uses: "not a number", "not finite" (inf, nan), "out of range (...)" (over- or underflow).
std::string parse_finite(const std::string& text, double& v);

// Parses `value` into *ref, checking the type, bounds and choices of the row described by the
// other arguments; errors read "<where>: parameter '<key>' = '<value>': <what is wrong>".
void set_setting_text(SettingRef ref, SettingType type, const std::string& key, double min, double max,
                      const std::vector<std::string>& choices, const std::string& value, const std::string& where);
// The value behind ref as text (17 digits) and typed (for HDF5 attributes).
std::string setting_text(SettingRef ref);
SettingValue setting_value(SettingRef ref);

template <class S>
const SettingField<S>* find_setting(const SettingTable<S>& table, const std::string& key) {
  for (const auto& f : table)
    if (f.key == key) return &f;
  return nullptr;
}
// Sets one key of s from text; an unknown key is an error listing the valid ones.
void throw_unknown_key(const std::vector<std::string>& valid, const std::string& key, const std::string& where);
template <class S>
void set_setting(const SettingTable<S>& table, S& s, const std::string& key, const std::string& value,
                 const std::string& where) {
  const SettingField<S>* f = find_setting(table, key);
  if (!f) {
    std::vector<std::string> keys;
    for (const auto& g : table) keys.push_back(g.key);
    throw_unknown_key(keys, key, where);
  }
  set_setting_text(f->ref(s), f->type, f->key, f->min, f->max, f->choices, value, where);
}
// Checks the values of s, filled in code rather than from text, against the table as if each had
// been set from its text: the same bounds, choices and messages.
template <class S>
void check_settings(const SettingTable<S>& table, const S& s, const std::string& where) {
  S scratch = s;
  for (const auto& f : table)
    set_setting_text(f.ref(scratch), f.type, f.key, f.min, f.max, f.choices, setting_text(f.ref(scratch)), where);
}
// Reads go through the same accessors; they never write.
template <class S>
std::string setting_text(const SettingField<S>& f, const S& s) { return setting_text(f.ref(const_cast<S&>(s))); }
template <class S>
SettingValue setting_value(const SettingField<S>& f, const S& s) { return setting_value(f.ref(const_cast<S&>(s))); }

}  // namespace xb
