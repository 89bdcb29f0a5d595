// The certificate of a reference substep (harness/sim/reference.hpp; docs/newton.md): how close
// the reference x_r is to the minimiser x* of E, and the proof that it is a minimiser. At x_r, with
// g = h²∇E(x_r) and K = h²∇²E(x_r) the exact Hessian on the free set (no element projected; the
// active bounds' y held, harness/sim/plane_bounds.hpp):
//  - minimiser: K factorises as positive definite (CHOLMOD's LLᵀ, solvers/direct/spd_factor.hpp):
//    with ‖∇E‖ small the second-order sufficient condition holds, x_r is near a strict local
//    minimiser, not a saddle;
//  - s = K⁻¹g, δ = ‖s‖_M: the Newton step not taken (x_r − x* = s to first order); δ_r = ‖K⁻¹n‖_M
//    for n a sample of g's rounding (newton.hpp: gradient_rounding_sample): the step rounding makes;
//  - the chord map T(x) = x − K⁻¹g(x), whose fixed point is x*: one more step from x⁺ = x_r − s,
//    s⁺ = K⁻¹g(x⁺) with the same factor, gives its contraction q = ‖s⁺‖_M/δ = ‖T(x⁺) − T(x_r)‖/‖x⁺ − x_r‖,
//    and a contraction's a-posteriori bound ‖x_r − x*‖_M ≤ κ(δ + δ_r), κ = 1/(1 − q);
//  - where ‖∇E‖ is at its rounding floor, s⁺ is rounding too and q says nothing: there κ = 2
//    (e ≤ δ + δ_r + βe² with a Lipschitz Hessian, and βe² ≤ e/2 this close to x*), or 1/(1 − q)
//    where that is smaller. Above the floor a q ≥ 1 gives no bound.
// tests/harness/sim/test_certificate.cpp checks the bound against the true error of every iterate
// of a solve run to its rounding floor.
#pragma once

#include "global_step.hpp"
#include "plane_bounds.hpp"

#include "../../problems/dual_system.hpp"
#include "../../problems/problem.hpp"
#include "../../solvers/direct/spd_factor.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <string>
#include <vector>

namespace xb {

struct Certificate {
  bool positive_definite = false;  // K on the free set factorised as positive definite
  std::string note;                // why there is no bound ("" where there is one)
  double gradient = 0, floor = 0;  // ‖∇E‖ of the free gradient at x_r and its rounding floor, N
  double newton_step = 0;          // δ
  double rounding_step = 0;        // δ_r
  double contraction = NAN;        // q
  double error_bound = INFINITY;   // κ(δ + δ_r), in ‖·‖_M; ∞: none
};

// κ above for a contraction q (NaN: none measured) at or above the rounding floor.
double error_bound_factor(double q, bool at_floor);

class MinimiserCertificate {
 public:
  // `step`: a GlobalStep of step = newton in the primal form with the full geometric stiffness
  // (the reference's); prob, ds, step and alpha_tilde must outlive this.
  MinimiserCertificate(const Problem& prob, const DualSystem& ds, GlobalStep& step, const Eigen::VectorXd& alpha_tilde,
                       double h);
  // The certificate of x for the substep predicted at x_pred.
  Certificate certify(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);

 private:
  double mass_norm(const Vector& dofs) const;  // ‖·‖_M of a vector on K's free dofs
  // v's free entries on K's dofs (the active set's y 0): out; then ‖K⁻¹v‖_M, or NaN if the solve failed.
  double step_norm(const Eigen::Matrix3Xd& v, Vector& out);
  // h²∇E at x into g_ (state_ and lambda_ at x).
  void gradient_at(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred);

  const Problem& prob_;
  const DualSystem& ds_;
  GlobalStep& step_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  PlaneBounds bounds_;
  SpdFactor factor_;
  ConstraintState state_;
  Eigen::VectorXd lambda_;
  Vector b_, g_dof_, v_dof_, s_;
  Eigen::Matrix3Xd g_, n_, x_plus_;
  std::vector<int> active_;
};

}  // namespace xb
