// Problem: particles, constraint batches, pins and colliders — only what a scene needs.
// Constraints are numbered globally: distance constraints first, then tet ARAP constraints.
#pragma once

#include "constraints.hpp"

#include <Eigen/Dense>

#include <array>
#include <string>
#include <vector>

namespace xb {

struct Particles {
  Eigen::Matrix3Xd x;      // positions, m
  Eigen::Matrix3Xd v;      // velocities, m/s
  Eigen::VectorXd w;       // inverse masses, 1/kg; 0 = pinned
  int size() const { return static_cast<int>(x.cols()); }
};

// A ground plane y = height: particles below it are projected onto it (as the paper does).
struct PlaneCollider {
  double height = 0;
};

struct Problem {
  std::string name;
  Particles particles;
  DistanceBatch distance;
  TetArapBatch tets;
  std::vector<PlaneCollider> planes;
  std::vector<std::array<int, 3>> surface;  // triangles for mesh output
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();

  int num_constraints() const { return static_cast<int>(distance.size() + tets.size()); }
  // Global constraint j's particles, padded with −1 (distance constraints use two).
  std::array<int, 4> constraint_particles(int j) const;
  double compliance(int j) const;
  // Throws xb::Error if an index is out of range, a pin list is wrong, or a value is not finite.
  void check() const;
};

// The state of all constraints at one x: values, gradients (4 per constraint, zero-padded).
struct ConstraintState {
  Eigen::VectorXd C;
  std::vector<std::array<Eigen::Vector3d, 4>> grad;
};

// Evaluates every constraint at x (in parallel); rest_epsilon: tet ARAP's gradient cut at rest
// (problems/constraints.hpp; 0 for Newton on E).
void evaluate_constraints(const Problem& prob, const Eigen::Matrix3Xd& x, ConstraintState& out,
                          double rest_epsilon = tet_rest_epsilon);

// Projects every free particle below a plane collider onto it (after each step, as the paper does).
void project_onto_planes(const Problem& prob, Eigen::Matrix3Xd& x);

// The total compliance vector α̃ = α/dt² of all constraints.
Eigen::VectorXd scaled_compliance(const Problem& prob, double dt);

}  // namespace xb
