#include "constraints.hpp"

#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 false positive inside Eigen::JacobiSVD
#include <Eigen/SVD>

#include <cmath>

namespace xb {

double distance_constraint(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double rest,
                           Eigen::Vector3d* grad_p, Eigen::Vector3d* grad_q) {
  const Eigen::Vector3d d = p - q;
  const double l = d.norm();
  if (grad_p) {
    const Eigen::Vector3d n = l > 0 ? Eigen::Vector3d(d / l) : Eigen::Vector3d::Zero();
    *grad_p = n;
    *grad_q = -n;
  }
  return l - rest;
}

void svd_rv(const Eigen::Matrix3d& F, Eigen::Matrix3d& U, Eigen::Vector3d& sigma, Eigen::Matrix3d& V) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  U = svd.matrixU();
  V = svd.matrixV();
  sigma = svd.singularValues();
  // Make U and V rotations; a reflection is moved into the smallest singular value.
  if (U.determinant() < 0) {
    U.col(2) *= -1;
    sigma(2) *= -1;
  }
  if (V.determinant() < 0) {
    V.col(2) *= -1;
    sigma(2) *= -1;
  }
}

double tet_arap_constraint(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                           const Eigen::Vector3d& x2, const Eigen::Vector3d& x3,
                           const Eigen::Matrix3d& Dm_inv, std::array<Eigen::Vector3d, 4>* grad, double rest_epsilon) {
  Eigen::Matrix3d Ds;
  Ds.col(0) = x1 - x0;
  Ds.col(1) = x2 - x0;
  Ds.col(2) = x3 - x0;
  const Eigen::Matrix3d F = Ds * Dm_inv;
  Eigen::Matrix3d U, V;
  Eigen::Vector3d s;
  svd_rv(F, U, s, V);
  return tet_arap_from_svd(F, U, s, V, Dm_inv, grad, rest_epsilon);
}

double tet_arap_from_svd(const Eigen::Matrix3d& F, const Eigen::Matrix3d& U, const Eigen::Vector3d& s,
                         const Eigen::Matrix3d& V, const Eigen::Matrix3d& Dm_inv, std::array<Eigen::Vector3d, 4>* grad,
                         double rest_epsilon) {
  const double C = std::sqrt((s.array() - 1.0).square().sum());
  if (grad) {
    if (C < rest_epsilon || C == 0) {
      for (auto& g : *grad) g.setZero();
    } else {
      const Eigen::Matrix3d dCdF = (F - U * V.transpose()) / C;
      const Eigen::Matrix3d G = dCdF * Dm_inv.transpose();
      (*grad)[1] = G.col(0);
      (*grad)[2] = G.col(1);
      (*grad)[3] = G.col(2);
      (*grad)[0] = -(G.col(0) + G.col(1) + G.col(2));
    }
  }
  return C;
}

}  // namespace xb
