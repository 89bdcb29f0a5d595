#include "refresh_rule.hpp"

#include "../../core/error.hpp"

#include <cmath>
#include <limits>

namespace xb::amg {

RefreshRule::RefreshRule(const std::string& mode, double growth) : growth_(growth) {
  if (mode == "full")
    mode_ = RefreshScope::full;
  else if (mode == "fine")
    mode_ = RefreshScope::fine;
  else if (mode == "keep")
    mode_ = RefreshScope::keep;
  else
    throw Error("amg.refresh: '" + mode + "' is not full, fine or keep");
  if (!(growth >= 1)) throw Error("amg.refresh_growth must be >= 1");
}

double RefreshRule::rate(int iterations, double relative_residual) {
  const double decades = -std::log10(relative_residual);
  if (!(decades > 0)) return std::numeric_limits<double>::infinity();  // no progress, or NaN
  return iterations / decades;
}

void RefreshRule::solved(int iterations, double relative_residual, bool ok) {
  if (!ok) {
    known_ = false;
    fresh_ = true;  // a breakdown: the next setup refreshes every level
    return;
  }
  if (iterations == 0) return;
  last_ = rate(iterations, relative_residual);
  if (fresh_) {
    reference_ = last_;
    fresh_ = false;
    known_ = true;
  }
}

RefreshScope RefreshRule::next() const {
  if (mode_ == RefreshScope::full || fresh_ || !known_) return RefreshScope::full;
  return last_ <= growth_ * reference_ ? mode_ : RefreshScope::full;
}

}  // namespace xb::amg
