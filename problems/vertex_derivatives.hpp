// One constraint seen from one of its particles (slot a), the others held fixed: what a block-
// coordinate method on the incremental potential needs per vertex (Vertex Block Descent, Chen et
// al. 2024; its augmented form, Giles et al. 2025; harness/sim/block_descent.hpp).
//   C, ∇_aC                     the value and particle a's gradient (rest_epsilon = 0, as Newton's)
//   energy block  (a, a) of π(∇²(½C²)) = π(∇C∇Cᵀ + C∇²C): VBD's Hessian of ½C²/α̃ is it over α̃
//   curvature     (a, a) of ∇²C (exact): AVBD's geometric term (kC + λ)∇²C, which it approximates
// Distance C = |p − q| − l₀: energy block nnᵀ + π(C/l)(I − nnᵀ), curvature (I − nnᵀ)/l (both slots;
// all zero at l = 0, as problems/constraint_hessian.hpp). Tet ARAP: with the closed-form eigensystem
// of problems/constraint_hessian.hpp (modes Q_k, eigenvalues ψ_k of ∇²_FΨ and c_k of ∇²_FC) and
// v_k = Q_k B(a, :)ᵀ (B the tet's shape gradients), energy block Σ_k π(ψ_k) v_k v_kᵀ, curvature
// Σ_k c_k v_k v_kᵀ: the (a, a) blocks of tet_energy_hessian and tet_arap_hessian without the 12×12.
// Since the modes are orthonormal, Σ_k v_kv_kᵀ = |B(a, :)|²I and only the three twists (ψ ≠ 1)
// and ĝ's scaling mode (c = 0) are built: one SVD and a few 3-vectors per tet and vertex.
// Checked against those and against finite differences in tests/problems/test_vertex_derivatives.cpp.
#pragma once

#include "constraint_hessian.hpp"
#include "problem.hpp"

#include <Eigen/Dense>

namespace xb {

struct VertexDerivatives {
  double C = 0;
  Eigen::Vector3d grad = Eigen::Vector3d::Zero();            // ∇_a C
  Eigen::Matrix3d energy = Eigen::Matrix3d::Zero();          // (a, a) of π(∇²(½C²))
  Eigen::Matrix3d curvature = Eigen::Matrix3d::Zero();       // (a, a) of ∇²C (only where asked)
};

// Constraint j of `prob` at x, seen from its slot `a` (0..1 for a distance, 0..3 for a tet).
// `curvature`: also fill the curvature block (AVBD); the energy block is always filled.
VertexDerivatives vertex_derivatives(const Problem& prob, const Eigen::Matrix3Xd& x, int j, int a, Projection proj,
                                     bool curvature);

}  // namespace xb
