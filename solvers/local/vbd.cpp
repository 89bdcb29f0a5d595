#include "vbd.hpp"

#include "../../core/error.hpp"
#include "../../problems/vertex_derivatives.hpp"

#include <cmath>
#include <limits>

namespace xb {

Coloring free_vertex_coloring(const Problem& prob) {
  std::vector<std::array<int, 4>> elements(prob.num_constraints());
  for (int j = 0; j < prob.num_constraints(); ++j) elements[j] = prob.constraint_particles(j);
  std::vector<char> active(prob.particles.size());
  for (int i = 0; i < prob.particles.size(); ++i) active[i] = prob.particles.w[i] > 0;
  return element_vertex_coloring(prob.particles.size(), elements, active);
}

Eigen::Vector3d block_step(const Eigen::Matrix3d& H, const Eigen::Vector3d& g, bool& skipped) {
  const Eigen::LLT<Eigen::Matrix3d> llt(H);
  skipped = llt.info() != Eigen::Success;
  if (skipped) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d dx = -llt.solve(g);
  skipped = !dx.allFinite();
  return skipped ? Eigen::Vector3d::Zero() : dx;
}

double ground_height(const Problem& prob) {
  double y = -std::numeric_limits<double>::infinity();
  for (const auto& plane : prob.planes) y = std::max(y, plane.height);
  return y;
}

VertexBlockDescent::VertexBlockDescent(const Problem& prob, const DualSystem& ds, const VbdSettings& s,
                                       const Eigen::VectorXd& alpha_tilde, double h)
    : prob_(prob), ds_(ds), s_(s), alpha_tilde_(alpha_tilde), h_(h),
      proj_(parse_projection(s.projection, "vbd.projection")), coloring_(free_vertex_coloring(prob)),
      ground_(ground_height(prob)) {
  for (long j = 0; j < alpha_tilde.size(); ++j)
    if (!(alpha_tilde[j] > 0))
      throw Error("solver 'vbd' needs every constraint compliant (alpha~ > 0): E(x) has no term for constraint " +
                  std::to_string(j) + " of compliance 0 (--solver avbd takes rigid constraints)");
}

void VertexBlockDescent::begin_substep(const Eigen::Matrix3Xd& x_t) {
  x_t_ = x_t;
  sweeps_ = 0;
  omega_ = 1;
}

Eigen::Vector3d VertexBlockDescent::vertex_step(int i, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred,
                                                bool& skipped) const {
  const double m = 1.0 / prob_.particles.w[i];
  Eigen::Vector3d g = m * (x.col(i) - x_pred.col(i));
  Eigen::Matrix3d He = Eigen::Matrix3d::Zero();
  const auto& start = ds_.incidence_start();
  for (int k = start[i]; k < start[i + 1]; ++k) {
    const auto [j, a] = ds_.incidence()[k];
    const VertexDerivatives d = vertex_derivatives(prob_, x, j, a, proj_, false);
    g += (d.C / alpha_tilde_[j]) * d.grad;
    He += d.energy / alpha_tilde_[j];
  }
  if (s_.damping > 0) {
    const double D = s_.damping / h_;
    g += D * (He * (x.col(i) - x_t_.col(i)));
    He *= 1 + D;
  }
  Eigen::Matrix3d H = He + m * Eigen::Matrix3d::Identity();
  if (x(1, i) < ground_) {
    const double kc = s_.contact_stiffness * m;
    g.y() += kc * (x(1, i) - ground_);
    H(1, 1) += kc;
  }
  return block_step(H, g, skipped);
}

void VertexBlockDescent::iterate(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred) {
  if (sweeps_ == 0 && s_.acceleration == "chebyshev") x_prev_ = x;  // x⁽⁰⁾
  skipped_ += coloured_sweep(coloring_, x, [&](int i, bool& skip) { return vertex_step(i, x, x_pred, skip); });
  ++sweeps_;
  if (s_.acceleration == "chebyshev") accelerate(x);
}

void VertexBlockDescent::accelerate(Eigen::Matrix3Xd& x) {
  const double rho2 = s_.rho * s_.rho;
  const int n = sweeps_;  // the paper's 1-based iteration number
  omega_ = n == 1 ? 1.0 : n == 2 ? 2.0 / (2.0 - rho2) : 4.0 / (4.0 - rho2 * omega_);
  if (n >= 2) x = omega_ * (x - x_prev2_) + x_prev2_;
  // x⁽ⁿ⁻²⁾ ← x⁽ⁿ⁻¹⁾, x⁽ⁿ⁻¹⁾ ← x⁽ⁿ⁾
  x_prev2_.swap(x_prev_);
  x_prev_ = x;
}

std::map<std::string, double> VertexBlockDescent::statistics() const {
  return {{"colors", coloring_.num_colors}, {"skipped_vertices", static_cast<double>(skipped_)}};
}

}  // namespace xb
