#include "record.hpp"

#include <cstdio>

namespace xb {

std::string attr_value_text(const AttrValue& v, int digits) {
  if (auto* i = std::get_if<long long>(&v)) return std::to_string(*i);
  if (auto* d = std::get_if<double>(&v)) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", digits, *d);
    return b;
  }
  return std::get<std::string>(v);
}

}  // namespace xb
