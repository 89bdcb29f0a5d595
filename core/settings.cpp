#include "settings.hpp"

#include "error.hpp"

#include <algorithm>
#include <cerrno>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace xb {

namespace {
std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}
}  // namespace

std::string parse_finite(const std::string& text, double& v) {
  errno = 0;
  char* end = nullptr;
  const double d = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || std::isspace(static_cast<unsigned char>(text[0])))
    return "not a number";
  // strtod says ERANGE for overflow (±HUGE_VAL) and underflow (a subnormal or 0): numbers a
  // double cannot hold, not malformed text; "inf" and "nan" written out are not finite.
  if (std::isnan(d) || (std::isinf(d) && errno != ERANGE)) return "not finite";
  if (errno == ERANGE && std::abs(d) > 1) return "out of range (too large for a double, above 1.8e308)";
  if (errno == ERANGE) return "out of range (too small for a double, below 2.2e-308; use 0 or a larger value)";
  v = d;
  return "";
}

void throw_unknown_key(const std::vector<std::string>& valid, const std::string& key, const std::string& where) {
  throw Error(where + ": unknown parameter '" + key + "' (valid: " + join(valid) + ")");
}

void set_setting_text(SettingRef ref, SettingType type, const std::string& key, double min, double max,
                      const std::vector<std::string>& choices, const std::string& value, const std::string& where) {
  auto bad = [&](const std::string& what) { return Error(where + ": parameter '" + key + "' = '" + value + "': " + what); };
  if (type == SettingType::String) {
    if (!choices.empty() && std::find(choices.begin(), choices.end(), value) == choices.end())
      throw bad("must be one of " + join(choices));
    *std::get<std::string*>(ref) = value;
    return;
  }
  double v = 0;
  if (const std::string why = parse_finite(value, v); !why.empty()) throw bad(why);
  if (v < min || v > max) {
    std::ostringstream os;
    os << "out of range [" << min << ", " << max << "]";
    throw bad(os.str());
  }
  if (type == SettingType::Int) {
    if (v != std::floor(v)) throw bad("must be an integer");
    *std::get<int*>(ref) = static_cast<int>(v);
  } else {
    *std::get<double*>(ref) = v;
  }
}

std::string setting_text(SettingRef ref) {
  std::ostringstream os;
  os.precision(17);
  std::visit([&](auto m) { os << *m; }, ref);
  return os.str();
}

SettingValue setting_value(SettingRef ref) {
  if (auto i = std::get_if<int*>(&ref)) return static_cast<long long>(**i);
  if (auto d = std::get_if<double*>(&ref)) return **d;
  return *std::get<std::string*>(ref);
}

}  // namespace xb
