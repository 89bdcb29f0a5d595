#include "problem.hpp"

#include "../core/error.hpp"

#include <cmath>
#include <string>

namespace xb {

std::array<int, 4> Problem::constraint_particles(int j) const {
  const int nd = static_cast<int>(distance.size());
  if (j < nd) return {distance.idx[j][0], distance.idx[j][1], -1, -1};
  return tets.idx[j - nd];
}

double Problem::compliance(int j) const {
  const int nd = static_cast<int>(distance.size());
  return j < nd ? distance.compliance[j] : tets.compliance[j - nd];
}

void Problem::check() const {
  const int n = particles.size();
  if (particles.v.cols() != n || particles.w.size() != n)
    throw Error(name + ": particle arrays have different lengths");
  if (!particles.x.allFinite()) throw Error(name + ": a particle position is not finite");
  for (int i = 0; i < n; ++i)
    if (!(particles.w[i] >= 0) || !std::isfinite(particles.w[i]))
      throw Error(name + ": particle " + std::to_string(i) + " has an invalid inverse mass");
  for (int j = 0; j < num_constraints(); ++j) {
    for (int p : constraint_particles(j))
      if (p < -1 || p >= n || (p == -1 && j >= static_cast<int>(distance.size())))
        throw Error(name + ": constraint " + std::to_string(j) + " has out-of-range particle index " +
                    std::to_string(p));
    if (!(compliance(j) >= 0)) throw Error(name + ": constraint " + std::to_string(j) + " has negative compliance");
  }
}

void evaluate_constraints(const Problem& prob, const Eigen::Matrix3Xd& x, ConstraintState& out, double rest_epsilon) {
  const int nd = static_cast<int>(prob.distance.size());
  const int m = prob.num_constraints();
  out.C.resize(m);
  out.grad.resize(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    auto& g = out.grad[j];
    if (j < nd) {
      const auto& e = prob.distance.idx[j];
      out.C[j] = distance_constraint(x.col(e[0]), x.col(e[1]), prob.distance.rest_length[j], &g[0], &g[1]);
      g[2].setZero();
      g[3].setZero();
    } else {
      const int t = j - nd;
      const auto& e = prob.tets.idx[t];
      out.C[j] = tet_arap_constraint(x.col(e[0]), x.col(e[1]), x.col(e[2]), x.col(e[3]), prob.tets.Dm_inv[t], &g, rest_epsilon);
    }
  }
}

void project_onto_planes(const Problem& prob, Eigen::Matrix3Xd& x) {
  for (const auto& plane : prob.planes)
    for (int p = 0; p < static_cast<int>(x.cols()); ++p)
      if (prob.particles.w[p] > 0 && x(1, p) < plane.height) x(1, p) = plane.height;
}

Eigen::VectorXd scaled_compliance(const Problem& prob, double dt) {
  const int m = prob.num_constraints();
  Eigen::VectorXd a(m);
  for (int j = 0; j < m; ++j) a[j] = prob.compliance(j) / (dt * dt);
  return a;
}

}  // namespace xb
