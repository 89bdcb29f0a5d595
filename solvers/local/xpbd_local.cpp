#include "xpbd_local.hpp"

#include "../../core/error.hpp"

#include <algorithm>

namespace xb {

namespace {
// xpbd-authors skips constraints already (nearly) satisfied: C ≤ this.
constexpr double authors_skip_below = 1e-6;
}  // namespace

LocalKind local_kind(const std::string& method) {
  if (method == "xpbd-jacobi") return LocalKind::jacobi;
  if (method == "xpbd-gs") return LocalKind::gauss_seidel;
  if (method == "xpbd-authors") return LocalKind::authors;
  throw Error("'" + method + "' is not a local method (valid: xpbd-jacobi, xpbd-gs, xpbd-authors)");
}

LocalMethod::LocalMethod(const Problem& prob, const DualSystem& ds, const XpbdSettings& s, LocalKind kind)
    : prob_(prob), ds_(ds), kind_(kind), gs_(kind == LocalKind::gauss_seidel), relaxation_(s.jacobi_relaxation) {
  if (gs_) coloring_ = greedy_coloring(ds.A());
  if (kind_ == LocalKind::authors) {
    relaxation_ = s.position_relaxation;
  } else if (relaxation_ == 0) {
    int n_max = 1;
    const auto& start = ds.incidence_start();
    for (int i = 0; i < prob.particles.size(); ++i)
      if (prob.particles.w[i] > 0) n_max = std::max(n_max, start[i + 1] - start[i]);
    relaxation_ = 1.0 / n_max;
  }
}

std::map<std::string, double> LocalMethod::statistics() const {
  switch (kind_) {
    case LocalKind::gauss_seidel: return {{"colors", coloring_.num_colors}};
    case LocalKind::jacobi: return {{"jacobi_relaxation_used", relaxation_}};
    case LocalKind::authors: return {{"authors_skipped_last_sweep", static_cast<double>(skipped_)}};
  }
  return {};
}

void LocalMethod::sweep(Eigen::Matrix3Xd& x, Eigen::VectorXd& lambda, const Eigen::VectorXd& alpha_tilde,
                        const ConstraintState& state) {
  if (!gs_) {
    jacobi_sweep(x, lambda, alpha_tilde, state);
    return;
  }
  const Eigen::VectorXd& w = prob_.particles.w;
  const int nd = static_cast<int>(prob_.distance.size());
  for (int c = 0; c < coloring_.num_colors; ++c) {
    const int begin = coloring_.color_start[c], end = coloring_.color_start[c + 1];
#pragma omp parallel for schedule(static)
    for (int q = begin; q < end; ++q) {
      const int j = coloring_.order[q];
      const auto ps = prob_.constraint_particles(j);
      std::array<Eigen::Vector3d, 4> g;
      double C;
      if (j < nd) {
        C = distance_constraint(x.col(ps[0]), x.col(ps[1]), prob_.distance.rest_length[j], &g[0], &g[1]);
        g[2].setZero();
        g[3].setZero();
      } else {
        C = tet_arap_constraint(x.col(ps[0]), x.col(ps[1]), x.col(ps[2]), x.col(ps[3]), prob_.tets.Dm_inv[j - nd], &g);
      }
      double Ajj = alpha_tilde[j];
      for (int s = 0; s < 4; ++s)
        if (ps[s] >= 0) Ajj += w[ps[s]] * g[s].squaredNorm();
      if (!(Ajj > 0)) continue;
      const double dl = (-C - alpha_tilde[j] * lambda[j]) / Ajj;
      lambda[j] += dl;
      for (int s = 0; s < 4; ++s)
        if (ps[s] >= 0 && w[ps[s]] > 0) x.col(ps[s]) += w[ps[s]] * dl * g[s];
    }
  }
}

void LocalMethod::jacobi_sweep(Eigen::Matrix3Xd& x, Eigen::VectorXd& lambda, const Eigen::VectorXd& alpha_tilde,
                               const ConstraintState& state) {
  const Eigen::VectorXd& w = prob_.particles.w;
  const int m = prob_.num_constraints();
  const bool authors = kind_ == LocalKind::authors;
  // xpbd-jacobi relaxes Δλ itself (λ and x stay consistent); xpbd-authors relaxes only Δx below.
  const double lambda_relaxation = authors ? 1.0 : relaxation_;
  dlambda_.resize(m);
  long long skipped = 0;
#pragma omp parallel for schedule(static) reduction(+ : skipped)
  for (int j = 0; j < m; ++j) {
    if (authors && state.C[j] <= authors_skip_below) {
      dlambda_[j] = 0;
      ++skipped;
      continue;
    }
    const auto ps = prob_.constraint_particles(j);
    double Ajj = alpha_tilde[j];
    for (int s = 0; s < 4; ++s)
      if (ps[s] >= 0) Ajj += w[ps[s]] * state.grad[j][s].squaredNorm();
    dlambda_[j] = Ajj > 0 ? lambda_relaxation * (-state.C[j] - alpha_tilde[j] * lambda[j]) / Ajj : 0.0;
  }
  skipped_ = skipped;
  lambda += dlambda_;
  ds_.apply_minv_gradT(state, dlambda_, dx_);
  if (authors) x += relaxation_ * dx_;
  else x += dx_;
}

}  // namespace xb
