#include "hessian_projection.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <utility>

namespace xb {

ProjectionStrategyKind parse_projection_strategy(const std::string& name) {
  using K = ProjectionStrategyKind;
  static const std::pair<const char*, K> kinds[] = {{"clamp", K::clamp},       {"abs", K::abs},
                                                    {"adaptive", K::adaptive}, {"on_demand", K::on_demand},
                                                    {"progressive", K::progressive}, {"rho_switch", K::rho_switch}};
  for (const auto& [text, kind] : kinds)
    if (name == text) return kind;
  std::string valid;
  for (const std::string& v : hessian_projection_choices()) valid += (valid.empty() ? "" : ", ") + v;
  throw Error("xpbd.hessian_projection: unknown strategy '" + name + "' (valid: " + valid + ")");
}

ProjectionStrategy::ProjectionStrategy(const Problem& prob, ProjectionStrategyKind kind, double exact_below)
    : prob_(prob), kind_(kind), exact_below_(exact_below) {}

void ProjectionStrategy::begin_substep() {
  model_held_ = true;
  tau_ = 1;
}

ElementProjection ProjectionStrategy::first(int it, double relative_gradient) {
  ElementProjection p;
  switch (kind_) {
    case ProjectionStrategyKind::clamp: break;
    case ProjectionStrategyKind::abs: p.base = Projection::abs; break;
    case ProjectionStrategyKind::adaptive:
      p.base = it > 0 && relative_gradient < exact_below_ ? Projection::none : Projection::clamp;
      break;
    case ProjectionStrategyKind::on_demand: p.base = Projection::none; break;
    case ProjectionStrategyKind::progressive:
      if (tau_ >= max_tau) p.base = Projection::none;
      p.tolerance = tau_;
      break;
    case ProjectionStrategyKind::rho_switch: p.base = model_held_ ? Projection::clamp : Projection::abs; break;
  }
  return p;
}

bool ProjectionStrategy::next(const ElementProjection& tried, ElementProjection& out) {
  if (!exact(tried)) return false;  // the projected K failed too: nothing left to try
  out = ElementProjection{Projection::clamp, 0};
  if (kind_ != ProjectionStrategyKind::progressive) return true;
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
