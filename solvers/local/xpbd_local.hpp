// The local XPBD methods: one sweep of Eq. 10 per outer iteration,
//   Δλ_j = (−C_j − α̃_j λ_j) / (∇C_j M⁻¹ ∇C_jᵀ + α̃_j),   Δx = M⁻¹ ∇C_jᵀ Δλ_j,
// dropping the off-diagonal terms of A.
//  - xpbd-gs: Gauss–Seidel, each constraint sees the positions its predecessors moved.
//    Parallelised by a greedy colouring of the constraint graph (constraints sharing a free
//    particle get different colours); within a colour no two constraints touch the same free
//    particle, so the result is the same for every thread count.
//  - xpbd-jacobi: every constraint computes Δλ from the same x; all updates are summed. Plain
//    summation overshoots wherever constraints share particles (Jacobi on A converges only if
//    ω < 2/ρ(D⁻¹A); ρ is 4–11 for edge constraints and larger for tet ARAP rows with ~69
//    non-zeros), so both λ and x take the relaxed step ω_J·Δλ, keeping λ consistent with x.
//    ω_J = xpbd.jacobi_relaxation; its default 0 means ω_J = 1/n_max, n_max the largest number
//    of constraints on one free particle: each particle then moves by at most the average of
//    its constraints' corrections (the averaging of Macklin et al. 2014, made uniform). It is
//    conservative (0.125 on the cloth grid, 1/24 inside the tet bar) but did not diverge on
//    any scene here, where ω_J = 0.25 diverges on bar_hang.
//  - xpbd-authors: the authors' XPBD baseline (their public code): a Jacobi sweep in which λ
//    takes the full Δλ but x only ω_x·Δx, ω_x = xpbd.position_relaxation (0.1), so λ runs ahead
//    of x; constraints with C ≤ 1e-6 are skipped (Δλ = 0). The skip is kept literally, one-sided
//    as theirs: meant for ARAP (C ≥ 0), it also skips every compressed distance constraint.
#pragma once

#include "../../problems/dual_system.hpp"
#include "xpbd_settings.hpp"
#include "../../problems/problem.hpp"
#include "../coloring.hpp"

#include <map>
#include <string>

namespace xb {

enum class LocalKind { jacobi, gauss_seidel, authors };
// The kind of a local method's name (xpbd-jacobi, xpbd-gs, xpbd-authors); throws for another name.
LocalKind local_kind(const std::string& method);

class LocalMethod {
 public:
  LocalMethod(const Problem& prob, const DualSystem& ds, const XpbdSettings& s, LocalKind kind);
  LocalMethod(const Problem& prob, const DualSystem& ds, const XpbdSettings& s, bool gauss_seidel)
      : LocalMethod(prob, ds, s, gauss_seidel ? LocalKind::gauss_seidel : LocalKind::jacobi) {}
  // One sweep: updates x and λ. `state` holds C and ∇C at the current x (Jacobi uses it;
  // Gauss–Seidel re-evaluates each constraint at the positions of the moment).
  void sweep(Eigen::Matrix3Xd& x, Eigen::VectorXd& lambda, const Eigen::VectorXd& alpha_tilde,
             const ConstraintState& state);
  // What the run records of this method: colors (xpbd-gs), jacobi_relaxation_used (xpbd-jacobi),
  // authors_skipped_last_sweep (xpbd-authors: constraints skipped, C ≤ 1e-6, in the last sweep).
  std::map<std::string, double> statistics() const;

 private:
  void jacobi_sweep(Eigen::Matrix3Xd& x, Eigen::VectorXd& lambda, const Eigen::VectorXd& alpha_tilde,
                    const ConstraintState& state);
  const Problem& prob_;
  const DualSystem& ds_;
  LocalKind kind_;
  bool gs_;
  double relaxation_;        // of λ and x (jacobi), of x only (authors)
  long long skipped_ = 0;
  Coloring coloring_;
  Eigen::VectorXd dlambda_;
  Eigen::Matrix3Xd dx_;
};

}  // namespace xb
