#include "element_hessians.hpp"

#include "../core/error.hpp"
#include "constraints.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace xb {

ElementHessians::ElementHessians(const Problem& prob) : prob_(prob) {
  const int n = prob.particles.size(), m = prob.num_constraints();
  inc_start_.assign(n + 1, 0);
  for (int j = 0; j < m; ++j)
    for (int p : prob.constraint_particles(j))
      if (p >= 0) ++inc_start_[p + 1];
  std::partial_sum(inc_start_.begin(), inc_start_.end(), inc_start_.begin());
  inc_.resize(inc_start_[n]);
  std::vector<int> pos(inc_start_.begin(), inc_start_.end() - 1);
  for (int j = 0; j < m; ++j) {
    const auto ps = prob.constraint_particles(j);
    for (int s = 0; s < 4; ++s)
      if (ps[s] >= 0) inc_[pos[ps[s]]++] = j << 2 | s;
  }
}

void ElementMatrices::resize(int num_distance, int num_tets) {
  nd_ = num_distance;
  nt_ = num_tets;
  values_.resize(36L * nd_ + 144L * nt_);
}

namespace {

// Constraint j's block by `distance(p, q, j)` or `tet(x0, x1, x2, x3, Dm_inv, t)`, padded to 12×12.
template <class Dist, class Tet>
Matrix12d element(const Problem& prob, const Eigen::Matrix3Xd& x, int j, Dist&& distance, Tet&& tet) {
  const int nd = static_cast<int>(prob.distance.size());
  if (j < nd) {
    const auto& e = prob.distance.idx[j];
    Matrix12d H = Matrix12d::Zero();
    H.topLeftCorner<6, 6>() = distance(x.col(e[0]), x.col(e[1]), j);
    return H;
  }
  const int t = j - nd;
  const auto& e = prob.tets.idx[t];
  return tet(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob.tets.Dm_inv[t], t);
}

Matrix12d geometric_stiffness_block(const Problem& prob, const Eigen::Matrix3Xd& x, int j, double lambda, Projection proj) {
  return element(
      prob, x, j, [&](const auto& p, const auto& q, int) { return distance_geometric_stiffness(p, q, lambda, proj); },
      [&](const auto& x0, const auto& x1, const auto& x2, const auto& x3, const auto& Dm_inv, int) {
        return tet_geometric_stiffness(x0, x1, x2, x3, Dm_inv, lambda, proj);
      });
}

}  // namespace

void ElementHessians::fill_geometric_stiffness(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda, Projection proj) {
  const int m = prob_.num_constraints();
  blocks_.resize(static_cast<int>(prob_.distance.size()), static_cast<int>(prob_.tets.size()));
  const int nd = static_cast<int>(prob_.distance.size());
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    const Matrix12d G = geometric_stiffness_block(prob_, x, j, lambda[j], proj);
    if (j < nd)
      blocks_.matrix(j) = G.topLeftCorner<6, 6>();
    else
      blocks_.matrix(j) = G;
  }
}

void ElementHessians::evaluate(const Eigen::Matrix3Xd& x, ConstraintState& state) {
  const int m = prob_.num_constraints(), nd = static_cast<int>(prob_.distance.size());
  state.C.resize(m);
  state.grad.resize(m);
  svd_.resize(prob_.tets.size());
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    auto& g = state.grad[j];
    if (j < nd) {
      const auto& e = prob_.distance.idx[j];
      state.C[j] = distance_constraint(x.col(e[0]), x.col(e[1]), prob_.distance.rest_length[j], &g[0], &g[1]);
      g[2].setZero();
      g[3].setZero();
    } else {
      const int t = j - nd;
      const auto& e = prob_.tets.idx[t];
      const Eigen::Matrix3d F = tet_deformation_gradient(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob_.tets.Dm_inv[t]);
      Svd& d = svd_[t];
      svd_rv(F, d.U, d.sigma, d.V);
      state.C[j] = tet_arap_from_svd(F, d.U, d.sigma, d.V, prob_.tets.Dm_inv[t], &g, 0.0);
    }
  }
}

void ElementHessians::fill_energy_hessian(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde,
                                          const ElementProjection& proj, ConstraintState* state, bool reuse_svd) {
  if (reuse_svd && (state || svd_.size() != prob_.tets.size()))
    throw Error("energy Hessian: reuse_svd needs a previous evaluate() and no state");
  const int m = prob_.num_constraints(), nd = static_cast<int>(prob_.distance.size());
  for (int j = 0; j < m; ++j)
    if (!(alpha_tilde[j] > 0))
      throw Error("energy Hessian: constraint " + std::to_string(j) + " has alpha~ = " + std::to_string(alpha_tilde[j]) +
                  " (E = sum C^2/(2 alpha) needs every alpha~ > 0)");
  blocks_.resize(nd, static_cast<int>(prob_.tets.size()));
  smallest_.resize(m);
  if (state) {
    state->C.resize(m);
    state->grad.resize(m);
  }
  int indefinite = 0, projected = 0;  // integer counts: any order gives the same sums
#pragma omp parallel for schedule(static) reduction(+ : indefinite, projected)
  for (int j = 0; j < m; ++j) {
    double* C = state ? &state->C[j] : nullptr;
    std::array<Eigen::Vector3d, 4>* g = state ? &state->grad[j] : nullptr;
    const Projection pj = proj.base;
    if (j < nd) {
      const auto& e = prob_.distance.idx[j];
      blocks_.matrix(j) = distance_energy_hessian(x.col(e[0]), x.col(e[1]), prob_.distance.rest_length[j], alpha_tilde[j],
                                                  pj, C, g ? &(*g)[0] : nullptr, g ? &(*g)[1] : nullptr, &smallest_[j],
                                                  proj.tolerance);
      if (g) (*g)[2].setZero(), (*g)[3].setZero();
    } else {
      const int t = j - nd;
      const auto& e = prob_.tets.idx[t];
      if (reuse_svd) {
        const Eigen::Matrix3d F = tet_deformation_gradient(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob_.tets.Dm_inv[t]);
        blocks_.matrix(j) = tet_energy_hessian_from_svd(F, svd_[t].U, svd_[t].sigma, svd_[t].V, prob_.tets.Dm_inv[t],
                                                        alpha_tilde[j], pj, &smallest_[j], proj.tolerance);
      } else {
        blocks_.matrix(j) = tet_energy_hessian(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob_.tets.Dm_inv[t],
                                               alpha_tilde[j], pj, C, g, &smallest_[j], proj.tolerance);
      }
    }
    if (smallest_[j] < 0) {
      ++indefinite;
      if (pj != Projection::none && smallest_[j] * alpha_tilde[j] < -proj.tolerance) ++projected;
    }
  }
  indefinite_ = indefinite;
  projected_ = projected;
}

double ElementHessians::lowest_mode(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& alpha_tilde, int j,
                                    Eigen::Matrix<double, 12, 1>& dx) const {
  const int nd = static_cast<int>(prob_.distance.size());
  dx.setZero();
  if (j < nd) {  // (I − nnᵀ) has the transverse eigenvalue 2C/(lα̃) along [t, −t], t ⟂ n
    const auto& e = prob_.distance.idx[j];
    const Eigen::Vector3d d = x.col(e[0]) - x.col(e[1]);
    const double l = d.norm();
    if (!(l > 0)) return 0;
    const Eigen::Vector3d n = d / l;
    int k = 0;
    n.cwiseAbs().minCoeff(&k);
    const Eigen::Vector3d t = n.cross(Eigen::Vector3d::Unit(k)).normalized();
    dx.segment<3>(0) = t;
    dx.segment<3>(3) = -t;
    return 4 * (l - prob_.distance.rest_length[j]) / (l * alpha_tilde[j]);  // [t, −t]ᵀ[B −B; −B B][t, −t] = 4tᵀBt
  }
  const int t = j - nd;
  if (static_cast<size_t>(t) >= svd_.size()) throw Error("lowest_mode: no evaluate() before it");
  const auto& e = prob_.tets.idx[t];
  const Eigen::Matrix3d F = tet_deformation_gradient(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob_.tets.Dm_inv[t]);
  const ArapEigensystem es = arap_eigensystem(F, svd_[t].U, svd_[t].sigma, svd_[t].V);
  int k = 0;
  const double psi = es.psi.minCoeff(&k);
  dx = tet_mode_displacement(es.mode[k], tet_shape_gradients(prob_.tets.Dm_inv[t]));
  return psi / alpha_tilde[j];
}

int ElementHessians::inverted_tets(double& smallest_twist_sum) const {
  int count = 0;
  double low = INFINITY;
  for (const Svd& d : svd_)
    if (d.sigma[2] < 0) {
      ++count;
      low = std::min(low, d.sigma[1] + d.sigma[2]);
    }
  smallest_twist_sum = low;
  return count;
}

void ElementHessians::geometric_stiffness_diagonal(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& lambda,
                                                   Eigen::Matrix3Xd& kd, Projection proj) {
  const int m = prob_.num_constraints(), n = prob_.particles.size();
  diag_.resize(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    const int nd = static_cast<int>(prob_.distance.size());
    Eigen::Matrix<double, 12, 1> d;
    if (j < nd) {
      d = geometric_stiffness_block(prob_, x, j, lambda[j], proj).diagonal();
    } else {
      const auto& e = prob_.tets.idx[j - nd];
      d = tet_geometric_stiffness_diagonal(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob_.tets.Dm_inv[j - nd],
                                           lambda[j], proj);
    }
    for (int s = 0; s < 4; ++s) diag_[j][s] = d.segment<3>(3 * s);
  }
  kd.resize(3, n);
  const Eigen::VectorXd& w = prob_.particles.w;
  // Per particle in incidence order (constraints ascending): the same sum every fill.
#pragma omp parallel for schedule(static)
  for (int p = 0; p < n; ++p) {
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k) acc += diag_[inc_[k] >> 2][inc_[k] & 3];
    kd.col(p) = w[p] > 0 ? Eigen::Vector3d(acc.cwiseMax(0.0)) : Eigen::Vector3d::Zero();
  }
}

void shifted_inverse_masses(const Eigen::VectorXd& w, const Eigen::Matrix3Xd& kd, Eigen::Matrix3Xd& w_dof) {
  const int n = static_cast<int>(w.size());
  w_dof.resize(3, n);
#pragma omp parallel for schedule(static)
  for (int p = 0; p < n; ++p)
    for (int d = 0; d < 3; ++d) w_dof(d, p) = w[p] > 0 ? 1.0 / (1.0 / w[p] + kd(d, p)) : 0.0;
}

}  // namespace xb
