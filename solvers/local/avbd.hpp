// Augmented Vertex Block Descent (Giles, Diaz and Yuksel, SIGGRAPH 2025; docs/vbd.md): VBD's sweep
// (solvers/local/vbd.hpp) on an augmented energy, in h²-units, that takes rigid constraints (α = 0)
// and the ground as hard constraints. Per constraint j a stiffness k_j and a multiplier λ_j (AVBD's
// sign: the force on x is −f_j∇C_j):
//   rigid (α̃ = 0)       f = kĈ + λ,  Ĉ = C − α·C(x_t) (the error a step starts with, corrected by 1 − α)
//   compliant distance, augmented  f = (kC + λ)/(1 + kα̃): the augmented Lagrangian of C(x) = s with
//                        s's energy ½s²/α̃ eliminated; its fixed point is λ = C/α̃, E's minimiser, for any k
//   compliant, penalty   f = kC, no multiplier, k ramped up to 1/α̃ (AVBD's finite stiffness): every
//                        tet (C = ‖F − R‖ ≥ 0 has no direction at rest for λ∇C), and distances under
//                        avbd.compliant = penalty. A rigid tet is refused.
//   ground (per particle, C = y − y₀ ≥ 0)  f = min(0, kĈ + λ), Ĉ = C − α·min(0, C(x_t))
// Each free vertex takes one Newton step on its block with a positive definite Hessian, k_eff = ∂f/∂C,
// (+ k e_y e_yᵀ where the ground pushes): avbd.hessian = projected: H_i = m_i I + Σ_j [the block of
// the energy's Hessian with its geometric part made PSD: k_eff∇C∇Cᵀ + max(f, 0)∇²C for a distance,
// kπ(∇²(½C²)) for a tet]; diagonal (AVBD's): m_i I + Σ_j [k_eff ∇_iC∇_iCᵀ + |f_j| diag(‖columns of
// ∇²_iiC_j‖)], which need not bound f∇²C from above (a tet ball in free fall diverged with it). After each sweep, from C at the new x (update_duals): the multiplier takes the
// force, λ ← f (rigid, augmented, ground: clamped to ≤ 0), and the stiffness ramps with the
// constraint's residual r (C − α̃λ; Ĉ for the ground, counted only where it pushes): κ ← min(κ + β|r|/c,
// κ_max) (penalty: k ≤ 1/α̃). k = κ·u, u = 1/Σ_a w_a G_a the constraint's mass (G_a = 1 for a distance,
// |B_a|² ≥ |∇_aC|² for a tet), c its length scale (a distance's rest length, 1 for a tet, the mean
// element size for the ground). Warm start of each step: λ ← αγλ, κ ← max(γκ, κ_start).
#pragma once

#include "vbd_settings.hpp"

#include "../coloring.hpp"
#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"

#include <map>
#include <string>
#include <vector>

namespace xb {

class AugmentedVbd {
 public:
  // prob, ds and alpha_tilde must outlive it. Throws xb::Error for a rigid tet.
  AugmentedVbd(const Problem& prob, const DualSystem& ds, const AvbdSettings& s, const Eigen::VectorXd& alpha_tilde);
  // The warm start of a new substep from its start x_t (the first: λ = 0, κ = κ_start).
  void begin_substep(const Eigen::Matrix3Xd& x_t);
  void sweep(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);
  // λ and k from C at x (`C`: every constraint's value there), after a sweep.
  void update_duals(const Eigen::Matrix3Xd& x, const Eigen::VectorXd& C);
  // The records' multipliers (XPBD's sign, −force) at x: −C/α̃ for a compliant constraint (E's own,
  // eliminated), −f for a rigid one.
  void multipliers(const Eigen::VectorXd& C, Eigen::VectorXd& lambda) const;
  // colors, skipped_vertices, and of the last sweep: the largest and median κ, ground_contacts.
  std::map<std::string, double> statistics() const;
  // Test access: constraint j's multiplier and stiffness (AVBD's sign, h²-units).
  double lambda(int j) const { return lambda_[j]; }
  double stiffness(int j) const { return k_[j]; }
  double ground_lambda(int p) const { return ground_lambda_[p]; }

 private:
  // f_j and k_eff at the value C (the constraint's force law above).
  void force(int j, double C, double& f, double& k_eff) const;
  void ground_force(int p, double y, double& f, double& k_eff) const;
  Eigen::Vector3d vertex_step(int i, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, bool& skipped) const;

  const Problem& prob_;
  const DualSystem& ds_;
  AvbdSettings s_;
  const Eigen::VectorXd& alpha_tilde_;
  bool diagonal_;  // avbd.hessian = diagonal
  enum class Mode { rigid, augmented, penalty };
  std::vector<Mode> mode_;  // per constraint
  Coloring coloring_;
  double ground_;
  bool started_ = false;
  // Per constraint: multiplier, stiffness, mass unit u, length scale c, C at the substep's start.
  std::vector<double> lambda_, k_, unit_, scale_, c0_;
  // Per particle, the ground: multiplier, stiffness, y − y₀ at the substep's start; its length scale.
  std::vector<double> ground_lambda_, ground_k_, ground_c0_;
  double ground_scale_ = 1;
  long long skipped_ = 0;
};

}  // namespace xb
