// Primal-form test systems built here, independent of the harness's form dispatch:
// K = M + Jᵀ diag(1/α̃) J over the free particles (node-major, 3 rows per particle), its
// right-hand side Jᵀα̃⁻¹b, the rigid-body modes at the current positions, and the dual system
// (A, b) of the same step, so a primal solve can be judged by the dual residual it implies.
#pragma once

#include "problems/dual_system.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

namespace xb::test {

struct PrimalCase {
  std::unique_ptr<Problem> prob;
  std::unique_ptr<DualSystem> ds;
  SparseMatrix J;           // m × 3·n_free
  Vector minv;              // 3·n_free: inverse masses per unknown
  Vector alpha_tilde;       // m
  SparseMatrix K;           // 3·n_free square, SPD
  Vector f;                 // Jᵀ α̃⁻¹ b
  Eigen::MatrixXd rigid;    // 3·n_free × 6: translations, then rotations about the centroid
  Vector b;                 // the dual right-hand side −(C + α̃λ)
  const SparseMatrix& A() const { return ds->A(); }
  // ‖J M⁻¹ r_K‖₂ / ‖b‖₂: the dual relative residual a primal residual implies.
  RelativeResidual dual_measure() const;
  // Δλ = α̃⁻¹(b − JΔx).
  Vector recover(const Vector& dx) const;
};

// The scene's spec with `overrides` (key, value) applied, simulated for `frames` frames by the
// dual XPBD step with a direct solve (so the state is one a simulation meets), then the primal
// system at the next frame's predicted state after `iterations` outer iterations.
PrimalCase primal_case(const std::string& scene, const std::vector<std::pair<std::string, std::string>>& overrides,
                       int frames = 0, int iterations = 0);

// The primal K of a small cloth (cloth_hang 24², 3 frames) at outer iterations 0 and 1: the same
// pattern, new values (the lazy setup's tests: test_hierarchy.cpp, test_refresh_rule.cpp).
struct TwoStates {
  PrimalCase a, b;
};
const TwoStates& two_cloth_states();

// K's pattern filled by new values: the same construction at a slightly moved state.
SparseMatrix primal_matrix(const Problem& prob, const Eigen::Matrix3Xd& x, double h, SparseMatrix* J_out = nullptr);

// Solver settings for the primal tests: tolerance `tol`, an iteration cap no test reaches.
inline Params solver_params(double tol) {
  Params p;
  p.linear.tol = tol;
  p.linear.max_iterations = 20000;
  return p;
}

// `method` on the case's K with its block size and rigid modes, optionally judged by `rel` (which
// the in-house solvers must accept).
inline LinearStats solve_k(const PrimalCase& c, const Params& p, const std::string& method, Vector& x,
                    const RelativeResidual& rel = nullptr) {
  auto s = make_linear_solver(method, p);
  if (rel) {
    EXPECT_TRUE(s->set_relative_residual(rel));
  }
  SetupContext ctx;
  ctx.block_size = 3;
  ctx.near_kernel = &c.rigid;
  s->setup(c.K, SetupKind::Structure, ctx);
  return s->solve(c.f, x);
}

// A small bar (stretched ARAP tets, one end pinned) and a small sagging cloth.
inline const PrimalCase& small_bar() {
  static const auto c = primal_case("bar_hang", {{"resolution", "3"}, {"aspect", "3"}}, 1, 0);
  return c;
}
inline const PrimalCase& small_cloth() {
  static const auto c = primal_case("cloth_hang", {{"resolution", "12"}}, 3, 0);
  return c;
}

}  // namespace xb::test
