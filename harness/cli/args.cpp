#include "args.hpp"

#include "../../core/error.hpp"
#include "../../core/settings.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace xb {

Args::Args(const std::string& command, const std::vector<std::string>& argv, const std::vector<FlagSpec>& spec,
           int max_positional)
    : command_(command) {
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.rfind("--", 0) != 0) {
      if (static_cast<int>(positional_.size()) >= max_positional)
        throw Error(command + ": unexpected argument '" + a + "'");
      positional_.push_back(a);
      continue;
    }
    std::string flag = a, value;
    bool inline_value = false;
    if (auto eq = a.find('='); eq != std::string::npos && a.rfind("--set", 0) != 0) {
      flag = a.substr(0, eq);
      value = a.substr(eq + 1);
      inline_value = true;
    }
    const FlagSpec* fs = nullptr;
    for (const auto& s : spec)
      if (s.name == flag) fs = &s;
    if (!fs) {
      std::string valid;
      for (const auto& s : spec) valid += (valid.empty() ? "" : ", ") + s.name;
      throw Error(command + ": unknown option '" + flag + "' (valid: " + valid + ")");
    }
    if (!fs->takes_value && inline_value)  // "--reference=no" must not mean yes
      throw Error(command + ": option " + flag + " takes no value (give " + flag + " alone, or leave it out)");
    if (fs->takes_value && !inline_value) {
      if (i + 1 >= argv.size()) throw Error(command + ": option " + flag + " needs a value");
      value = argv[++i];
    }
    if (!fs->repeatable && values_.count(flag)) throw Error(command + ": option " + flag + " given twice");
    values_[flag].push_back(value);
  }
}

std::string Args::get(const std::string& flag, const std::string& fallback) const {
  auto it = values_.find(flag);
  return it == values_.end() ? fallback : it->second.back();
}

std::string Args::require(const std::string& flag) const {
  auto it = values_.find(flag);
  if (it == values_.end() || it->second.back().empty()) throw Error(command_ + ": option " + flag + " is required");
  return it->second.back();
}

const std::vector<std::string>& Args::all(const std::string& flag) const {
  static const std::vector<std::string> none;
  auto it = values_.find(flag);
  return it == values_.end() ? none : it->second;
}

double Args::get_double(const std::string& flag, double fallback) const {
  if (!has(flag)) return fallback;
  const std::string v = get(flag);
  double d = 0;
  if (const std::string why = parse_finite(v, d); !why.empty())
    throw Error(command_ + ": option " + flag + " = '" + v + "': " + why);
  return d;
}

int Args::get_int(const std::string& flag, int fallback) const {
  const double d = get_double(flag, fallback);
  if (d != std::floor(d)) throw Error(command_ + ": option " + flag + " = '" + get(flag) + "' must be an integer");
  if (std::abs(d) > std::numeric_limits<int>::max())
    throw Error(command_ + ": option " + flag + " = '" + get(flag) + "' is out of range (|value| <= " +
                std::to_string(std::numeric_limits<int>::max()) + ")");
  return static_cast<int>(d);
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace xb
