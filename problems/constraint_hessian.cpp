#include "constraint_hessian.hpp"

#include "../core/error.hpp"
#include "constraints.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

const std::vector<std::string>& projection_choices() {
  static const std::vector<std::string> v = {"none", "clamp", "abs"};
  return v;
}

Projection parse_projection(const std::string& name, const std::string& where) {
  if (name == "none") return Projection::none;
  if (name == "clamp") return Projection::clamp;
  if (name == "abs") return Projection::abs;
  throw Error(where + ": unknown projection '" + name + "' (valid: none, clamp, abs)");
}

std::string projection_name(Projection p) { return projection_choices()[static_cast<int>(p)]; }

double project_eigenvalue(double mu, Projection p) {
  switch (p) {
    case Projection::clamp: return std::max(mu, 0.0);
    case Projection::abs: return std::abs(mu);
    default: return mu;
  }
}

namespace {

// [B −B; −B B] for a 3×3 block B.
Matrix6d pair_block(const Eigen::Matrix3d& B) {
  Matrix6d H;
  H << B, -B, -B, B;
  return H;
}

}  // namespace

Matrix6d distance_hessian(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d d = p - q;
  const double l = d.norm();
  if (!(l > 0)) return Matrix6d::Zero();
  const Eigen::Vector3d n = d / l;
  return pair_block((Eigen::Matrix3d::Identity() - n * n.transpose()) / l);
}

Matrix6d distance_geometric_stiffness(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double lambda, Projection proj) {
  const Eigen::Vector3d d = p - q;
  const double l = d.norm();
  if (!(l > 0)) return Matrix6d::Zero();
  const Eigen::Vector3d n = d / l;
  return pair_block(project_eigenvalue(-lambda / l, proj) * (Eigen::Matrix3d::Identity() - n * n.transpose()));
}

Matrix6d distance_energy_hessian(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double rest, double alpha_tilde,
                                 Projection proj, double* C, Eigen::Vector3d* grad_p, Eigen::Vector3d* grad_q,
                                 double* smallest, double tolerance) {
  Eigen::Vector3d gp, gq;
  const double c = distance_constraint(p, q, rest, &gp, &gq);
  if (C) *C = c;
  if (grad_p) *grad_p = gp, *grad_q = gq;
  const double l = (p - q).norm();
  if (smallest) *smallest = l > 0 ? std::min(c / l, 1.0) / alpha_tilde : 0.0;
  if (!(l > 0)) return Matrix6d::Zero();
  const Eigen::Matrix3d nn = gp * gp.transpose();
  const double transverse = c / l < -tolerance ? project_eigenvalue(c / l, proj) : c / l;
  return pair_block((nn + transverse * (Eigen::Matrix3d::Identity() - nn)) / alpha_tilde);
}

ArapEigensystem arap_eigensystem(const Eigen::Matrix3d& F) {
  Eigen::Matrix3d U, V;
  Eigen::Vector3d s;
  svd_rv(F, U, s, V);
  return arap_eigensystem(F, U, s, V);
}

ArapEigensystem arap_eigensystem(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& s,
                                 const Eigen::Matrix3d& V) {
  (void)F;
  ArapEigensystem es;
  es.C = std::sqrt((s.array() - 1.0).square().sum());
  const bool at_rest = es.C < tet_rest_epsilon;
  // Scaling subspace: ĝ = (σ − 1)/C and two unit vectors orthogonal to it (any basis at rest).
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (!at_rest) {
    const Eigen::Vector3d g = (s.array() - 1.0).matrix() / es.C;
    // Householder reflection taking e_k (k the largest |g_k|) to g: its columns are orthonormal.
    int k = 0;
    g.cwiseAbs().maxCoeff(&k);
    const Eigen::Vector3d v = g - Eigen::Vector3d::Unit(k);
    if (v.norm() > 1e-14) S -= 2.0 * v * v.transpose() / v.squaredNorm();
    S.col(k).swap(S.col(0));  // column 0 is ĝ
  }
  // The modes as sums of outer products uᵢvⱼᵀ (cheaper than U·E·Vᵀ with a sparse E).
  std::array<Eigen::Matrix3d, 3> uv;  // uᵢvᵢᵀ
  for (int i = 0; i < 3; ++i) uv[i] = U.col(i) * V.col(i).transpose();
  for (int a = 0; a < 3; ++a) {
    es.mode[a] = S(0, a) * uv[0] + S(1, a) * uv[1] + S(2, a) * uv[2];
    es.psi[a] = 1;
    es.c[a] = a == 0 ? 0.0 : 1.0;
  }
  const double r = 1.0 / std::sqrt(2.0);
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int t = 0; t < 3; ++t) {
    const int i = pairs[t][0], j = pairs[t][1];
    const Eigen::Matrix3d ij = r * U.col(i) * V.col(j).transpose(), ji = r * U.col(j) * V.col(i).transpose();
    es.mode[3 + t] = ij - ji;
    es.mode[6 + t] = ij + ji;
    es.psi[3 + t] = 1.0 - 2.0 / std::max(s[i] + s[j], tet_twist_epsilon);
    es.psi[6 + t] = 1;
    es.c[3 + t] = es.psi[3 + t];
    es.c[6 + t] = 1;
  }
  es.c = at_rest ? Eigen::Matrix<double, 9, 1>::Zero() : Eigen::Matrix<double, 9, 1>(es.c / es.C);
  return es;
}

Eigen::Matrix3d tet_deformation_gradient(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                         const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv) {
  Eigen::Matrix3d Ds;
  Ds.col(0) = x1 - x0;
  Ds.col(1) = x2 - x0;
  Ds.col(2) = x3 - x0;
  return Ds * Dm_inv;
}

Eigen::Matrix<double, 4, 3> tet_shape_gradients(const Eigen::Matrix3d& Dm_inv) {
  Eigen::Matrix<double, 4, 3> B;
  B.bottomRows<3>() = Dm_inv;
  B.row(0) = -Dm_inv.colwise().sum();
  return B;
}

namespace {

// Column k is D vec(Q_k): particle a's 3 entries are Q_k·B(a, :)ᵀ, the columns of Q_k Bᵀ.
Eigen::Matrix<double, 12, 9> modes_in_x(const ArapEigensystem& es, const Eigen::Matrix<double, 4, 3>& B) {
  Eigen::Matrix<double, 12, 9> W;
  for (int k = 0; k < 9; ++k) {
    const Eigen::Matrix<double, 3, 4> QB = es.mode[k] * B.transpose();
    W.col(k) = Eigen::Map<const Eigen::Matrix<double, 12, 1>>(QB.data());
  }
  return W;
}

}  // namespace

Matrix12d tet_modes_to_x(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu,
                         const Eigen::Matrix<double, 4, 3>& B) {
  const Eigen::Matrix<double, 12, 9> W = modes_in_x(es, B);
  const Eigen::Matrix<double, 12, 9> Wmu = W * mu.asDiagonal();
  // The upper triangle only, mirrored: exactly symmetric (K's blocks (p, q) and (q, p) stay
  // transposes) at 78 of the 144 dot products.
  Matrix12d H;
  for (int c = 0; c < 12; ++c)
    for (int r = 0; r <= c; ++r) H(r, c) = H(c, r) = Wmu.row(r).dot(W.row(c));
  return H;
}

Eigen::Matrix<double, 12, 1> tet_modes_diagonal(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu,
                                                const Eigen::Matrix<double, 4, 3>& B) {
  return modes_in_x(es, B).array().square().matrix() * mu;
}

Eigen::Matrix<double, 12, 1> tet_mode_displacement(const Eigen::Matrix3d& Q, const Eigen::Matrix<double, 4, 3>& B) {
  const Eigen::Matrix<double, 3, 4> dX = Q * (B.transpose() * B).inverse() * B.transpose();
  return Eigen::Map<const Eigen::Matrix<double, 12, 1>>(dX.data());
}

Matrix9d tet_modes_to_F(const ArapEigensystem& es, const Eigen::Matrix<double, 9, 1>& mu) {
  Matrix9d H = Matrix9d::Zero();
  for (int k = 0; k < 9; ++k) {
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> q(es.mode[k].data());
    H.noalias() += mu[k] * q * q.transpose();
  }
  return (H + H.transpose()) * 0.5;
}

Matrix12d tet_arap_hessian(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                           const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv) {
  const ArapEigensystem es = arap_eigensystem(tet_deformation_gradient(x0, x1, x2, x3, Dm_inv));
  return tet_modes_to_x(es, es.c, tet_shape_gradients(Dm_inv));
}

Matrix12d tet_geometric_stiffness(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                  const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv, double lambda, Projection proj) {
  const ArapEigensystem es = arap_eigensystem(tet_deformation_gradient(x0, x1, x2, x3, Dm_inv));
  Eigen::Matrix<double, 9, 1> mu;
  for (int k = 0; k < 9; ++k) mu[k] = project_eigenvalue(-lambda * es.c[k], proj);
  return tet_modes_to_x(es, mu, tet_shape_gradients(Dm_inv));
}

Eigen::Matrix<double, 12, 1> tet_geometric_stiffness_diagonal(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                                              const Eigen::Vector3d& x2, const Eigen::Vector3d& x3,
                                                              const Eigen::Matrix3d& Dm_inv, double lambda, Projection proj) {
  const ArapEigensystem es = arap_eigensystem(tet_deformation_gradient(x0, x1, x2, x3, Dm_inv));
  Eigen::Matrix<double, 9, 1> mu;
  for (int k = 0; k < 9; ++k) mu[k] = project_eigenvalue(-lambda * es.c[k], proj);
  return tet_modes_diagonal(es, mu, tet_shape_gradients(Dm_inv));
}

Matrix12d tet_energy_hessian(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                             const Eigen::Vector3d& x3, const Eigen::Matrix3d& Dm_inv, double alpha_tilde, Projection proj,
                             double* C, std::array<Eigen::Vector3d, 4>* grad, double* smallest, double tolerance) {
  const Eigen::Matrix3d F = tet_deformation_gradient(x0, x1, x2, x3, Dm_inv);
  Eigen::Matrix3d U, V;
  Eigen::Vector3d s;
  svd_rv(F, U, s, V);
  // tet_arap_constraint's C and ∇C with Newton's rest_epsilon = 0, from the same SVD
  const double c = tet_arap_from_svd(F, U, s, V, Dm_inv, grad, 0.0);
  if (C) *C = c;
  return tet_energy_hessian_from_svd(F, U, s, V, Dm_inv, alpha_tilde, proj, smallest, tolerance);
}

Matrix12d tet_energy_hessian_from_svd(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& s,
                                      const Eigen::Matrix3d& V, const Eigen::Matrix3d& Dm_inv, double alpha_tilde,
                                      Projection proj, double* smallest, double tolerance) {
  const ArapEigensystem es = arap_eigensystem(F, U, s, V);
  const double lowest = es.psi.minCoeff();
  if (lowest >= -tolerance) proj = Projection::none;
  Eigen::Matrix<double, 9, 1> mu;
  for (int k = 0; k < 9; ++k) mu[k] = project_eigenvalue(es.psi[k] / alpha_tilde, proj);
  if (smallest) *smallest = lowest / alpha_tilde;
  return tet_modes_to_x(es, mu, tet_shape_gradients(Dm_inv));
}

}  // namespace xb
