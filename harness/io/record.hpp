// A run as a results file holds it: its scalars as attributes, its per-iteration arrays as
// datasets (the schema is results/README.md). Written and read by recorder.hpp.
#pragma once

#include <map>
#include <string>
#include <variant>
#include <vector>

namespace xb {

using AttrValue = std::variant<long long, double, std::string>;
using DataValue = std::variant<std::vector<double>, std::vector<long long>, std::vector<std::string>>;

struct RunRecord {
  std::string name;                          // group name under /runs
  std::map<std::string, AttrValue> attrs;
  std::map<std::string, DataValue> datasets;  // a '/' in a name makes subgroups
};

constexpr int schema_version = 1;

// An attribute as text: integers and strings as they are, doubles with `digits` significant
// digits (17 reads back bit for bit; 3 for table cells).
std::string attr_value_text(const AttrValue& v, int digits);

}  // namespace xb
