#include "settings.hpp"

#include "error.hpp"

#include <algorithm>
#include <cerrno>
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
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size()) throw bad("not a number");
  // strtod says ERANGE for both overflow (±HUGE_VAL) and underflow (a subnormal or 0): both are
  // numbers outside what the key accepts, not malformed text; "inf" and "nan" are written out.
  if (errno != ERANGE && !std::isfinite(v)) throw bad("not finite");
  if (errno == ERANGE || v < min || v > max) {
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
