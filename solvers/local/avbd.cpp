#include "avbd.hpp"

#include "vbd.hpp"

#include "../../core/error.hpp"
#include "../../problems/constraint_hessian.hpp"
#include "../../problems/constraints.hpp"
#include "../../problems/vertex_derivatives.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

AugmentedVbd::AugmentedVbd(const Problem& prob, const DualSystem& ds, const AvbdSettings& s, const Eigen::VectorXd& alpha_tilde)
    : prob_(prob), ds_(ds), s_(s), alpha_tilde_(alpha_tilde), diagonal_(s.hessian == "diagonal"),
      coloring_(free_vertex_coloring(prob)),
      ground_(ground_height(prob)) {
  const int m = prob.num_constraints(), nd = static_cast<int>(prob.distance.size()), n = prob.particles.size();
  const Eigen::VectorXd& w = prob.particles.w;
  lambda_.assign(m, 0);
  mode_.assign(m, Mode::penalty);
  k_.assign(m, 0);
  unit_.assign(m, 0);
  scale_.assign(m, 1);
  c0_.assign(m, 0);
  double lengths = 0;
  for (int j = 0; j < m; ++j) {
    const auto ps = prob.constraint_particles(j);
    double inv = 0;  // Σ_a w_a G_a
    if (j < nd) {
      inv = w[ps[0]] + w[ps[1]];
      scale_[j] = prob.distance.rest_length[j] > 0 ? prob.distance.rest_length[j] : 1.0;
      lengths += prob.distance.rest_length[j];
    } else {
      const Eigen::Matrix<double, 4, 3> B = tet_shape_gradients(prob.tets.Dm_inv[j - nd]);
      for (int a = 0; a < 4; ++a) inv += w[ps[a]] * B.row(a).squaredNorm();
      lengths += std::cbrt(6 * prob.tets.rest_volume[j - nd]);
    }
    unit_[j] = inv > 0 ? 1.0 / inv : 0.0;  // 0: no free particle, the constraint never acts
    // A tet's C = ‖F − R‖ ≥ 0 is a cone at rest, where a multiplier's force λ∇C has no direction:
    // with one, the ball in free fall diverged from rounding-level C (docs/vbd.md). Tets keep the
    // penalty form; a rigid one has no form here.
    if (!(alpha_tilde[j] > 0) && j >= nd)
      throw Error("solver 'avbd' takes rigid distance constraints, not rigid tets (constraint " + std::to_string(j) +
                  "): C = |F - R| >= 0 has no direction at rest for a multiplier's force");
    if (!(alpha_tilde[j] > 0)) mode_[j] = Mode::rigid;
    else if (j < nd && s.compliant == "augmented") mode_[j] = Mode::augmented;
  }
  if (m > 0 && lengths > 0) ground_scale_ = lengths / m;
  if (!prob.planes.empty()) {
    ground_lambda_.assign(n, 0);
    ground_k_.assign(n, 0);
    ground_c0_.assign(n, 0);
  }
}

void AugmentedVbd::begin_substep(const Eigen::Matrix3Xd& x_t) {
  const double decay = s_.alpha * s_.gamma;
  const int m = static_cast<int>(k_.size()), nd = static_cast<int>(prob_.distance.size());
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    const bool soft = alpha_tilde_[j] > 0;
    double k = started_ ? std::max(s_.gamma * k_[j], s_.stiffness_start * unit_[j]) : s_.stiffness_start * unit_[j];
    if (mode_[j] == Mode::penalty) k = std::min(k, 1.0 / alpha_tilde_[j]);
    k_[j] = k;
    lambda_[j] = started_ && mode_[j] != Mode::penalty ? decay * lambda_[j] : 0.0;
    if (soft) continue;
    const auto ps = prob_.constraint_particles(j);  // the error a rigid constraint starts with
    c0_[j] = j < nd ? distance_constraint(x_t.col(ps[0]), x_t.col(ps[1]), prob_.distance.rest_length[j], nullptr, nullptr)
                    : tet_arap_constraint(x_t.col(ps[0]), x_t.col(ps[1]), x_t.col(ps[2]), x_t.col(ps[3]),
                                          prob_.tets.Dm_inv[j - nd], nullptr, 0.0);
  }
  const Eigen::VectorXd& w = prob_.particles.w;
  for (size_t p = 0; p < ground_k_.size(); ++p) {
    if (!(w[p] > 0)) continue;
    const double start = s_.stiffness_start / w[p];
    ground_k_[p] = started_ ? std::max(s_.gamma * ground_k_[p], start) : start;
    ground_lambda_[p] = started_ ? decay * ground_lambda_[p] : 0.0;
    ground_c0_[p] = x_t(1, p) - ground_;
  }
  started_ = true;
}

void AugmentedVbd::force(int j, double C, double& f, double& k_eff) const {
  const double k = k_[j], a = alpha_tilde_[j];
  if (mode_[j] == Mode::rigid) {
    f = k * (C - s_.alpha * c0_[j]) + lambda_[j];
    k_eff = k;
  } else if (mode_[j] == Mode::penalty) {
    f = k * C;
    k_eff = k;
  } else {
    const double d = 1 + k * a;
    f = (k * C + lambda_[j]) / d;
    k_eff = k / d;
  }
}

void AugmentedVbd::ground_force(int p, double y, double& f, double& k_eff) const {
  const double C = y - ground_, t = ground_k_[p] * (C - s_.alpha * std::min(0.0, ground_c0_[p])) + ground_lambda_[p];
  f = std::min(0.0, t);
  k_eff = t < 0 ? ground_k_[p] : 0.0;
}

Eigen::Vector3d AugmentedVbd::vertex_step(int i, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                                          bool& skipped) const {
  const double m = 1.0 / prob_.particles.w[i];
  const int nd = static_cast<int>(prob_.distance.size());
  Eigen::Vector3d g = m * (x.col(i) - x_pred.col(i));
  Eigen::Matrix3d H = m * Eigen::Matrix3d::Identity();
  const auto& start = ds_.incidence_start();
  for (int k = start[i]; k < start[i + 1]; ++k) {
    const auto [j, a] = ds_.incidence()[k];
    const bool tet = j >= nd;
    const VertexDerivatives d = vertex_derivatives(prob_, x, j, a, Projection::clamp, diagonal_ || !tet);
    double f, k_eff;
    force(j, d.C, f, k_eff);
    g += f * d.grad;
    if (diagonal_) {  // AVBD's stand-in for the indefinite f∇²C: the diagonal of its column norms
      H += k_eff * d.grad * d.grad.transpose();
      for (int c = 0; c < 3; ++c) H(c, c) += std::abs(f) * d.curvature.col(c).norm();
    } else if (tet) {  // penalty: ∇²(½kC²) = kπ(∇²Ψ), VBD's projected block
      H += k_eff * d.energy;
    } else {  // k_eff nnᵀ + f(I − nnᵀ)/l, its transverse eigenvalue clamped at 0
      H += k_eff * d.grad * d.grad.transpose() + std::max(f, 0.0) * d.curvature;
    }
  }
  if (!ground_k_.empty()) {
    double f, k_eff;
    ground_force(i, x(1, i), f, k_eff);
    g.y() += f;
    H(1, 1) += k_eff;
  }
  return block_step(H, g, skipped);
}

void AugmentedVbd::sweep(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  skipped_ += coloured_sweep(coloring_, x, [&](int i, bool& skip) { return vertex_step(i, x, x_pred, skip); });
}

void AugmentedVbd::update_duals(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& C) {
  const int m = static_cast<int>(k_.size());
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    if (unit_[j] == 0) continue;
    const double a = alpha_tilde_[j];
    double f, k_eff, r;
    force(j, C[j], f, k_eff);
    if (mode_[j] == Mode::rigid) {
      r = C[j] - s_.alpha * c0_[j];
    } else if (mode_[j] == Mode::penalty) {
      r = C[j];
    } else {
      r = C[j] - a * lambda_[j];
    }
    const double k = k_[j] + s_.beta * unit_[j] * std::abs(r) / scale_[j];
    k_[j] = mode_[j] == Mode::penalty ? std::min(k, 1.0 / a) : std::min(k, s_.stiffness_max * unit_[j]);
    if (mode_[j] != Mode::penalty) lambda_[j] = f;
  }
  const Eigen::VectorXd& w = prob_.particles.w;
  for (size_t p = 0; p < ground_k_.size(); ++p) {
    if (!(w[p] > 0)) continue;
    const double Chat = x(1, p) - ground_ - s_.alpha * std::min(0.0, ground_c0_[p]);
    ground_lambda_[p] = std::min(0.0, ground_k_[p] * Chat + ground_lambda_[p]);
    if (ground_lambda_[p] < 0)
      ground_k_[p] = std::min(ground_k_[p] + s_.beta * std::abs(Chat) / (w[p] * ground_scale_), s_.stiffness_max / w[p]);
  }
}

void AugmentedVbd::multipliers(const Eigen::VectorXd& C, Eigen::VectorXd& lambda) const {
  const int m = static_cast<int>(k_.size());
  lambda.resize(m);
  for (int j = 0; j < m; ++j) {
    double f, k_eff;
    force(j, C[j], f, k_eff);
    lambda[j] = alpha_tilde_[j] > 0 ? -C[j] / alpha_tilde_[j] : -f;
  }
}

std::map<std::string, double> AugmentedVbd::statistics() const {
  std::vector<double> kappa;
  for (size_t j = 0; j < k_.size(); ++j)
    if (unit_[j] > 0) kappa.push_back(k_[j] / unit_[j]);
  std::map<std::string, double> out = {{"colors", coloring_.num_colors}, {"skipped_vertices", static_cast<double>(skipped_)}};
  if (!kappa.empty()) {
    std::sort(kappa.begin(), kappa.end());
    out["avbd_kappa_max"] = kappa.back();
    out["avbd_kappa_median"] = kappa[kappa.size() / 2];
  }
  if (!ground_k_.empty())
    out["ground_contacts"] = static_cast<double>(std::count_if(ground_lambda_.begin(), ground_lambda_.end(), [](double l) { return l < 0; }));
  return out;
}

}  // namespace xb
