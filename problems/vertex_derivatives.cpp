#include "vertex_derivatives.hpp"

#include "constraints.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

namespace {

VertexDerivatives distance_vertex(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double rest, int a, Projection proj,
                                  bool curvature) {
  VertexDerivatives d;
  Eigen::Vector3d gp, gq;
  d.C = distance_constraint(p, q, rest, &gp, &gq);
  d.grad = a == 0 ? gp : gq;
  const double l = (p - q).norm();
  if (!(l > 0)) return d;
  const Eigen::Matrix3d nn = gp * gp.transpose(), transverse = Eigen::Matrix3d::Identity() - nn;
  d.energy = nn + project_eigenvalue(d.C / l, proj) * transverse;
  if (curvature) d.curvature = transverse / l;
  return d;
}

// With y = Vᵀb, a twist mode's vector is v_t = (y_j U_i − y_i U_j)/√2; the nine modes are an
// orthonormal basis of F-space, so Σ_k v_kv_kᵀ = |b|²I, and only the twists (ψ_t = 1 − 2/(σ_i + σ_j),
// the one eigenvalue that is not 1) and, for ∇²C, the scaling mode along ĝ (c = 0) differ from it.
VertexDerivatives tet_vertex(const Problem& prob, const Eigen::Matrix3Xd& x, int t, int a, Projection proj, bool curvature) {
  const auto& e = prob.tets.idx[t];
  const Eigen::Matrix3d& Dm_inv = prob.tets.Dm_inv[t];
  const Eigen::Matrix3d F = tet_deformation_gradient(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), Dm_inv);
  Eigen::Matrix3d U, V;
  Eigen::Vector3d s;
  svd_rv(F, U, s, V);
  const Eigen::Vector3d b = a == 0 ? Eigen::Vector3d(-Dm_inv.colwise().sum().transpose()) : Eigen::Vector3d(Dm_inv.row(a - 1).transpose());
  VertexDerivatives d;
  d.C = std::sqrt((s.array() - 1.0).square().sum());  // tet_arap_from_svd's C, bit for bit
  if (d.C > 0) d.grad = (F - U * V.transpose()) * b / d.C;
  const Eigen::Vector3d y = V.transpose() * b;
  const double bb = b.squaredNorm();
  d.energy = bb * Eigen::Matrix3d::Identity();
  if (curvature) d.curvature = d.energy;
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (const auto& [i, j] : pairs) {
    const Eigen::Vector3d v = (y[j] * U.col(i) - y[i] * U.col(j)) / std::sqrt(2.0);
    const double psi = 1.0 - 2.0 / std::max(s[i] + s[j], tet_twist_epsilon);
    const Eigen::Matrix3d vv = v * v.transpose();
    d.energy += (project_eigenvalue(psi, proj) - 1) * vv;
    if (curvature) d.curvature += (psi - 1) * vv;
  }
  if (curvature) {  // ∇²C = (∇²Ψ − ∇C∇Cᵀ)/C off its kink (problems/constraint_hessian.hpp), 0 below it
    if (d.C < tet_rest_epsilon) d.curvature.setZero();
    else d.curvature = (d.curvature - d.grad * d.grad.transpose()) / d.C;
  }
  return d;
}

}  // namespace

VertexDerivatives vertex_derivatives(const Problem& prob, const Eigen::Matrix3Xd& x, int j, int a, Projection proj,
                                     bool curvature) {
  const int nd = static_cast<int>(prob.distance.size());
  if (j < nd) {
    const auto& e = prob.distance.idx[j];
    return distance_vertex(x.col(e[0]), x.col(e[1]), prob.distance.rest_length[j], a, proj, curvature);
  }
  return tet_vertex(prob, x, j - nd, a, proj, curvature);
}

}  // namespace xb
