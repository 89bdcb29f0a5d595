#include "trust_region.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

Globalization parse_globalization(const std::string& name, const std::string& key) {
  if (name == "line_search") return Globalization::line_search;
  if (name == "trust_region") return Globalization::trust_region;
  throw Error(key + ": unknown globalization '" + name + "' (valid: line_search, trust_region)");
}

TrustRegionSubproblem parse_trust_region_subproblem(const std::string& name, const std::string& key) {
  if (name == "steihaug") return TrustRegionSubproblem::steihaug;
  if (name == "more_sorensen") return TrustRegionSubproblem::more_sorensen;
  throw Error(key + ": unknown trust-region subproblem solver '" + name + "' (valid: steihaug, more_sorensen)");
}

double RadiusRule::next(double radius, double rho, double step, bool boundary) {
  if (!(rho >= shrink_below)) return shrink * std::min(radius, step);  // NaN too
  if (rho > grow_above && boundary) return grow * radius;
  return radius;
}

}  // namespace xb
