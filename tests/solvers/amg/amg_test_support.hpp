// What the AMG tests share: model Poisson matrices, seeded random vectors and the dual system
// of a scene after a few outer iterations.
#pragma once

#include "problems/dual_system.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"
#include "solvers/amg/hierarchy.hpp"
#include "solvers/linear_solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace xb::test {

inline SparseMatrix poisson2d(int n) {
  std::vector<Eigen::Triplet<double>> t;
  auto id = [n](int i, int j) { return i * n + j; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      t.emplace_back(id(i, j), id(i, j), 4.0);
      if (i > 0) t.emplace_back(id(i, j), id(i - 1, j), -1.0);
      if (i + 1 < n) t.emplace_back(id(i, j), id(i + 1, j), -1.0);
      if (j > 0) t.emplace_back(id(i, j), id(i, j - 1), -1.0);
      if (j + 1 < n) t.emplace_back(id(i, j), id(i, j + 1), -1.0);
    }
  SparseMatrix A(n * n, n * n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

inline SparseMatrix poisson3d(int n) {
  std::vector<Eigen::Triplet<double>> t;
  auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const int r = id(i, j, k);
        t.emplace_back(r, r, 6.0);
        if (i > 0) t.emplace_back(r, id(i - 1, j, k), -1.0);
        if (i + 1 < n) t.emplace_back(r, id(i + 1, j, k), -1.0);
        if (j > 0) t.emplace_back(r, id(i, j - 1, k), -1.0);
        if (j + 1 < n) t.emplace_back(r, id(i, j + 1, k), -1.0);
        if (k > 0) t.emplace_back(r, id(i, j, k - 1), -1.0);
        if (k + 1 < n) t.emplace_back(r, id(i, j, k + 1), -1.0);
      }
  SparseMatrix A(n * n * n, n * n * n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

inline Vector random_vector(long n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Vector v(n);
  for (long i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

// The dual system of a scene at its first outer iteration: positions predicted under gravity
// from the scene's start (bar_hang starts pre-stretched, so every ARAP gradient is defined),
// then `iterations` outer iterations with CHOLMOD so the matrix is one a simulation meets.
struct SceneSystem {
  Problem prob;
  std::unique_ptr<DualSystem> ds;
  Vector b;
};

inline SceneSystem scene_system(const std::string& scene, int resolution, int iterations) {
  Params p;
  load_scene_file(resolve_scene(scene), p);
  p.resolution = resolution;
  SceneSystem s;
  s.prob = build_problem(p);
  Particles& P = s.prob.particles;
  const double h = p.dt / p.substeps;
  for (int i = 0; i < P.size(); ++i)
    if (P.w[i] > 0) P.x(1, i) += h * h * p.gravity;
  s.ds = std::make_unique<DualSystem>(s.prob);
  const Vector at = scaled_compliance(s.prob, h);
  Vector lambda = Vector::Zero(s.prob.num_constraints());
  auto direct = make_linear_solver("cholmod", p);
  ConstraintState st;
  for (int it = 0;; ++it) {
    evaluate_constraints(s.prob, P.x, st);
    s.ds->fill(st, at);
    s.b = -(st.C + at.cwiseProduct(lambda));
    if (it == iterations) break;
    direct->setup(s.ds->A(), SetupKind::Structure, {});
    Vector dl;
    direct->solve(s.b, dl);
    lambda += dl;
    Eigen::Matrix3Xd dx;
    s.ds->apply_minv_gradT(st, dl, dx);
    P.x += dx;
  }
  return s;
}

// What ⟨Mx, y⟩ − ⟨x, My⟩ is measured against: ‖x‖‖y‖, or the scale-free √(⟨Mx, x⟩⟨My, y⟩) for
// K, whose large entries make M's values small.
enum class SymmetryScale { norms, energy };

// ⟨Mx, y⟩ vs ⟨x, My⟩ (to 1e-10 of the scale) and ⟨Mx, x⟩ > 0 for the V-cycle operator M.
inline void check_vcycle_spd(amg::Hierarchy& h, int trials, const std::string& what,
                             SymmetryScale scale = SymmetryScale::norms) {
  const long n = h.matrix(0).rows();
  for (int t = 0; t < trials; ++t) {
    const Vector x = random_vector(n, 100 + 2 * t), y = random_vector(n, 101 + 2 * t);
    Vector Mx, My;
    h.vcycle(x, Mx);
    h.vcycle(y, My);
    const double ref = scale == SymmetryScale::norms ? x.norm() * y.norm() : std::sqrt(std::abs(Mx.dot(x) * My.dot(y)));
    EXPECT_LE(std::abs(Mx.dot(y) - x.dot(My)), 1e-10 * ref) << what;
    EXPECT_GT(Mx.dot(x), 0) << what;
    EXPECT_GT(My.dot(y), 0) << what;
  }
}

inline double rel_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

}  // namespace xb::test
