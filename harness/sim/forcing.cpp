#include "forcing.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

namespace {
// Eisenstat & Walker's threshold below which the safeguard is not applied.
constexpr double kSafeguardThreshold = 0.1;
}  // namespace

ForcingRule::ForcingRule(const LinearSettings& s) : s_(s), fixed_(s.forcing == "fixed") {}

double ForcingRule::next(int k, double residual) {
  if (fixed_) return s_.tol;
  double eta = s_.forcing_max;
  if (k > 0 && previous_residual_ > 0) {
    eta = s_.forcing_gamma * std::pow(residual / previous_residual_, s_.forcing_alpha);
    const double safeguard = s_.forcing_gamma * std::pow(previous_eta_, s_.forcing_alpha);
    if (safeguard > kSafeguardThreshold) eta = std::max(eta, safeguard);
    eta = std::min(eta, s_.forcing_max);
  }
  eta = std::max(eta, s_.tol);
  previous_residual_ = residual;
  previous_eta_ = eta;
  return eta;
}

}  // namespace xb
