// The outer loop of the block-descent methods (docs/vbd.md): `--solver vbd` (Vertex Block Descent,
// solvers/local/vbd.hpp) and `--solver avbd` (its augmented form, solvers/local/avbd.hpp) on the
// incremental potential E of one substep — the E Newton minimises (harness/sim/newton.hpp), so their
// truth is the same reference. Per substep: the start x⁽⁰⁾ by vbd.init (VBD §3.7) projected onto the
// ground's bounds (Newton's start is x̃'s projection), then per
// iteration: evaluate (C, E, ‖∇E‖ at x) → the hooks → stop test → [avbd: λ, k from C] → one sweep.
// The stop test is Newton's (newton_loop.hpp): ‖∇E‖ of the free gradient (the ground's active
// bounds left out, plane_bounds.hpp; a particle below the ground counts its natural residual)
// against rtol·‖∇E(x̃)‖ (x̃ on the bounds: the same scale as Newton's and every method's relative
// Newton residual) and atol, its rounding floor, max_iterations.
// Where some constraint is rigid (avbd) ∇E is not defined: the measure is the Newton residual
// √(‖g‖² + ‖C_rigid‖²), g = M(x − x̃) − Jᵀλ with λ = −C/α̃ (compliant) and AVBD's force (rigid).
// rtol = atol = 0 with max_iterations = N is the fixed-iteration frame users run.
#pragma once

#include "newton_loop.hpp"
#include "plane_bounds.hpp"
#include "stop_reason.hpp"

#include "../params.hpp"
#include "../../problems/dual_system.hpp"
#include "../../solvers/local/avbd.hpp"
#include "../../solvers/local/vbd.hpp"

#include <functional>
#include <map>
#include <optional>
#include <string>

namespace xb {

// What the loop shows its caller at every evaluation.
struct BlockDescentIterate {
  int iteration;
  const Eigen::Matrix3Xd& x;
  const ConstraintState& state;
  const Eigen::VectorXd& lambda;  // XPBD's sign: −C/α̃ (compliant), −AVBD's force (rigid)
  double gradient, gradient0;     // the stop test's measure (above), now and at x̃
  double primal0, dual0;          // ‖g‖ (free, h²-units) and ‖C_rigid‖ at x̃: the scale of the relative Newton residual
  double primal, dual;            // the same now
  double floor;                   // the measure's rounding floor (every α̃ > 0; else 0)
  double energy;
  int active;                     // particles held on a plane (the free gradient's active bounds)
  double sweep_time;              // s of the sweep that led here (0 at iteration 0)
};

struct BlockDescentHooks {
  std::function<void(const BlockDescentIterate&)> on_iterate;
  std::function<bool()> proceed;  // before each sweep; false: stop (interrupted)
};

class BlockDescentLoop {
 public:
  // `method`: vbd or avbd. prob, ds and alpha_tilde must outlive the loop. Throws xb::Error for vbd
  // with a rigid constraint.
  BlockDescentLoop(const Problem& prob, const DualSystem& ds, const Params& p, const std::string& method,
                   const Eigen::VectorXd& alpha_tilde, double h);
  // One substep from x_t (the step's start) with velocities v_t before gravity's kick (x̃ = x_t +
  // h v_t + h² g at the free particles); x ends at the last iterate.
  NewtonOutcome minimise(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_t, const Eigen::Matrix3Xd& x_pred,
                         const Eigen::Matrix3Xd& v_t, const BlockDescentHooks& hooks);
  std::map<std::string, double> statistics() const;

 private:
  // C, ∇C, λ, g, the free gradient and the measure at x (at_start: x̃, every rigid λ = 0).
  void evaluate(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, bool at_start);
  // The free gradient's entries of the particles below the ground.
  void below_plane(const Eigen::Matrix3Xd& x, Eigen::Matrix3Xd& free) const;
  // x⁽⁰⁾ by vbd.init.
  void start(Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, const Eigen::Matrix3Xd& v_t);

  const Problem& prob_;
  const DualSystem& ds_;
  const Eigen::VectorXd& alpha_tilde_;
  double h_;
  StopCriterion stop_;  // Newton's: rtol, atol, max_iterations on ‖∇E‖
  std::string init_;
  bool all_compliant_;
  std::optional<VertexBlockDescent> vbd_;
  std::optional<AugmentedVbd> avbd_;
  PlaneBounds bounds_;
  ConstraintState state_;
  Eigen::VectorXd lambda_;
  Eigen::Matrix3Xd g_, x_t_, v_prev_;
  std::vector<int> active_;
  double primal_ = 0, dual_ = 0, measure_ = 0;
  bool have_v_prev_ = false;
};

}  // namespace xb
