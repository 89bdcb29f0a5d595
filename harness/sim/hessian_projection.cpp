#include "hessian_projection.hpp"

#include "../../core/error.hpp"

#include <algorithm>

namespace xb {

ProjectionStrategy::ProjectionStrategy(const Problem& prob, const std::string& name, double exact_below)
    : prob_(prob), name_(name), exact_below_(exact_below) {
  const auto& v = hessian_projection_choices();
  if (std::find(v.begin(), v.end(), name) == v.end())
    throw Error("xpbd.hessian_projection: unknown strategy '" + name +
                "' (valid: clamp, abs, adaptive, on_demand, progressive, trust_region)");
}

void ProjectionStrategy::begin_substep() {
  model_held_ = true;
  tau_ = 1;
}

ElementProjection ProjectionStrategy::first(int it, double relative_gradient) {
  ElementProjection p;
  if (name_ == "abs") {
    p.base = Projection::abs;
  } else if (name_ == "adaptive") {
    p.base = it > 0 && relative_gradient < exact_below_ ? Projection::none : Projection::clamp;
  } else if (name_ == "on_demand") {
    p.base = Projection::none;
  } else if (name_ == "progressive") {
    if (tau_ >= max_tau) p.base = Projection::none;
    p.tolerance = tau_;
  } else if (name_ == "trust_region") {
    p.base = model_held_ ? Projection::clamp : Projection::abs;
  }
  return p;
}

bool ProjectionStrategy::next(const ElementProjection& tried, ElementProjection& out) {
  if (!exact(tried)) return false;  // the projected K failed too: nothing left to try
  out = ElementProjection{Projection::clamp, 0};
  if (name_ != "progressive") return true;
  tau_ = tau_ > 0.1 ? 0.1 : 0;  // to 0.1, then every element clamped
  out.tolerance = tau_;
  return true;
}

void ProjectionStrategy::after_step(double actual, double predicted) {
  model_held_ = predicted > 0 && actual >= 0.25 * predicted;
  // progressive: a step the quadratic model predicted well lets more elements stay exact.
  if (predicted > 0 && actual >= 0.75 * predicted) tau_ = tau_ > 0 ? std::min(10 * tau_, max_tau) : 0.1;
}

}  // namespace xb
