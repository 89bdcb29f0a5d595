// Vertex Block Descent (Chen, Liu, Yang and Yuksel, SIGGRAPH 2024; docs/vbd.md): block-coordinate
// descent on the incremental potential of one substep, in h²-units
//   h²E(x) = ½‖x − x̃‖²_M + Σ_j ½C_j²/α̃_j   (+ VBD's ground penalty Σ_p ½k̃_c min(0, y_p − y₀)²)
// One sweep visits the free vertices colour by colour (element_vertex_coloring: no two vertices of
// one colour share a constraint, so a colour runs in parallel and the result is the same for any
// thread count); each vertex i takes one Newton step on its own 3×3 block, the others fixed:
//   g_i = m_i(x_i − x̃_i) + Σ_j (C_j/α̃_j)∇_iC_j,   H_i = m_i I + Σ_j π(∇²(½C_j²))_ii/α̃_j,   x_i ← x_i − H_i⁻¹g_i,
// each element's Hessian made PSD before its vertex block is taken (vbd.projection, the closed forms
// of problems/vertex_derivatives.hpp), so H_i ⪰ m_i I; a vertex whose block is not positive definite
// is skipped (block_step: the paper skips a singular one; only vbd.projection = none can meet it).
// Ground contact as VBD's penalty: for y_p below the highest plane y₀, g_y += k̃_c(y_p − y₀), H_yy += k̃_c,
// k̃_c = vbd.contact_stiffness·m_p. Damping (vbd.damping = k_d, off by default) as VBD's per-vertex form:
// g_i += (k_d/h)H_e(x_i − x_i^t), H_e ← (1 + k_d/h)H_e for the elastic part H_e (then the sweep no
// longer minimises E). Acceleration (§3.8, vbd.acceleration = chebyshev): after sweep n (1-based),
// x ← ω_n(x̄ − x⁽ⁿ⁻²⁾) + x⁽ⁿ⁻²⁾ for n ≥ 2, ω_1 = 1, ω_2 = 2/(2 − ρ²), ω_n = 4/(4 − ρ²ω_{n−1}).
#pragma once

#include "vbd_settings.hpp"

#include "../coloring.hpp"
#include "../../problems/constraint_hessian.hpp"
#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <map>
#include <string>

namespace xb {

// One Gauss–Seidel sweep in colour order: the vertices of one colour in parallel (no two share an
// element), x_i += step(i, skip) each; returns how many were skipped (a singular block).
template <class Step>
long long coloured_sweep(const Coloring& coloring, Eigen::Matrix3Xd& x, Step&& step) {
  long long skipped = 0;
  for (int c = 0; c < coloring.num_colors; ++c) {
    const int begin = coloring.color_start[c], end = coloring.color_start[c + 1];
#pragma omp parallel for schedule(static) reduction(+ : skipped)
    for (int q = begin; q < end; ++q) {
      const int i = coloring.order[q];
      bool skip = false;
      x.col(i) += step(i, skip);
      if (skip) ++skipped;
    }
  }
  return skipped;
}

// −H⁻¹g by a 3×3 Cholesky; zero and `skipped` where H is not positive definite (VBD skips a vertex
// whose block is singular, |det H| ≤ ε; here also an indefinite one, whose step would not descend).
Eigen::Vector3d block_step(const Eigen::Matrix3d& H, const Eigen::Vector3d& g, bool& skipped);

// The particles a block-descent method moves (w > 0) and its colouring of them.
Coloring free_vertex_coloring(const Problem& prob);
// The highest ground plane's y (−inf without planes).
double ground_height(const Problem& prob);

class VertexBlockDescent {
 public:
  // prob, ds and alpha_tilde must outlive it; throws xb::Error where some α̃ = 0 (E has no term for a
  // rigid constraint: --solver avbd takes them).
  VertexBlockDescent(const Problem& prob, const DualSystem& ds, const VbdSettings& s, const Eigen::VectorXd& alpha_tilde,
                     double h);
  // A new substep starting from x_t (damping's reference, the acceleration's x⁽⁰⁾ is the first iterate).
  void begin_substep(const Eigen::Matrix3Xd& x_t);
  // One sweep (and the acceleration) from x; `x_pred` is x̃.
  void iterate(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);
  // colors; skipped_vertices (over the run: blocks found singular).
  std::map<std::string, double> statistics() const;

 private:
  // The Newton step of vertex i on its block (zero where skipped).
  Eigen::Vector3d vertex_step(int i, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, bool& skipped) const;
  void accelerate(Eigen::Matrix3Xd& x);

  const Problem& prob_;
  const DualSystem& ds_;
  VbdSettings s_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  Projection proj_;
  Coloring coloring_;
  double ground_;
  Eigen::Matrix3Xd x_t_, x_prev_, x_prev2_;  // damping's x^t; the last two iterates (acceleration)
  int sweeps_ = 0;                           // in this substep
  double omega_ = 1;
  long long skipped_ = 0;
};

}  // namespace xb
