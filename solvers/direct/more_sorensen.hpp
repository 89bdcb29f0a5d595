// Moré–Sorensen: the trust-region subproblem
//   min m(p) = gᵀp + ½pᵀKp   subject to ‖p‖_D ≤ Δ   (D SPD: a diagonal, or a matrix of K's pattern),
// K symmetric and possibly indefinite, solved nearly exactly by factorising K + σD with a direct
// solver (Moré & Sorensen 1983; Nocedal–Wright, Numerical Optimization, Algorithm 4.3). The
// solution is p(σ) = −(K + σD)⁻¹g with K + σD positive semi-definite, σ ≥ 0 and σ(Δ − ‖p‖_D) = 0;
// σ comes from the secular equation 1/‖p(σ)‖_D = 1/Δ by safeguarded Newton steps,
//   σ ← σ + (‖p‖_D/‖q‖)²(‖p‖_D − Δ)/Δ,   ‖q‖² = (Dp)ᵀ(K + σD)⁻¹(Dp),
// inside a bracket [σ_L, σ_U]: σ_L from K's diagonal, Gershgorin and a given direction of negative
// curvature u (σ ≥ −uᵀKu/uᵀDu), raised by every failed factorisation (K + σD not positive definite);
// σ_U from ‖g‖_{D⁻¹}/Δ + ‖D^-½KD^-½‖_∞ for a diagonal D (a matrix D: none until a step is inside,
// σ grown fourfold until then). The hard case (g ⟂ the lowest eigenvector, ‖p(σ)‖_D < Δ at
// the bracket's floor) is closed along u: p + τu on the boundary when its curvature term is small
// (Moré–Sorensen's test τ²uᵀ(K + σD)u ≤ κ(2 − κ)(pᵀ(K + σD)p + σΔ²)).
#pragma once

#include "../linear_solver.hpp"

#include <memory>
#include <string>

namespace xb {

// The region's norm ‖p‖²_D = pᵀDp: a positive diagonal, or a sparse SPD matrix with exactly K's
// pattern (K + σD is then formed entry by entry).
struct RegionNorm {
  const Vector* diagonal = nullptr;
  const SparseMatrix* matrix = nullptr;
  double dot(const Vector& a, const Vector& b) const;  // aᵀDb
  void apply(const Vector& a, Vector& out) const;       // D a
};

struct MoreSorensenResult {
  Vector p;
  double sigma = 0;        // the shift of the accepted p
  double model = 0;        // m(p), from one product Kp
  double norm = 0;         // ‖p‖_D
  int factorisations = 0;  // of K + σD, the failed ones included
  int failed = 0;          // of them, not positive definite
  bool boundary = false;   // σ > 0: on the boundary (within the accuracy)
  bool hard_case = false;  // closed along u
  bool ok = false;         // false: no shift gave a positive definite K + σD (message says why)
  std::string message;
  Vector Kp;
};

class MoreSorensen {
 public:
  // accuracy κ: |‖p‖_D − Δ| ≤ κΔ ends the iteration (Moré–Sorensen's σ₁; 0.1 in their tests).
  MoreSorensen(std::unique_ptr<LinearSolver> direct, double accuracy = 0.1, int max_factorisations = 30);
  // u: a direction of negative curvature of K (or null / empty). K's pattern is analysed at the
  // first call and whenever it changes.
  MoreSorensenResult solve(const SparseMatrix& K, const RegionNorm& D, const Vector& g, double radius,
                           const Vector* u = nullptr);
  MoreSorensenResult solve(const SparseMatrix& K, const Vector& D, const Vector& g, double radius,
                           const Vector* u = nullptr) {
    return solve(K, RegionNorm{&D, nullptr}, g, radius, u);
  }
  const LinearSolver& solver() const { return *direct_; }

 private:
  // S = K + σD; false where the factorisation failed (not positive definite).
  bool factorise(const SparseMatrix& K, const RegionNorm& D, double sigma);
  std::unique_ptr<LinearSolver> direct_;
  double kappa_;
  int max_factorisations_;
  SparseMatrix S_;
  std::vector<int> diag_;  // S's value index of each diagonal entry
  bool analysed_ = false;
};

}  // namespace xb
