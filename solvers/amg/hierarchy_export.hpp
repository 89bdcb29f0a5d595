// The levels of a built hierarchy (hierarchy.hpp) as plain CSR matrices and vectors, for another
// implementation of the solve phase to run the same V-cycle (the Python package's GPU path,
// python/xpbd_bench/gpu.py, and the capture files it benchmarks). One function reads the levels,
// through Hierarchy's public accessors: whatever the hierarchy stores inside (node blocks, float
// copies), this is the one place that has to say what the V-cycle applies.
#pragma once

#include "hierarchy.hpp"

#include <array>
#include <string>
#include <vector>

namespace xb::amg {

// A level's smoother. The polynomial kinds (jacobi, chebyshev, block_jacobi, block_chebyshev) are
// given in full: a sweep is `steps` in order, each d = c1·d + c2·D⁻¹(b − A x), then x += d (from
// x = 0 the first step is d = c2·D⁻¹b); the same sweeps before and after the coarse correction.
// The Gauss–Seidel kinds only by name (polynomial = false).
struct SmootherExport {
  std::string kind;
  bool polynomial = false;
  int sweeps = 0, degree = 0;
  double lambda_max = 0;               // the λ_max(D⁻¹A) in use (amg.jacobi_omega = level0: level 0's)
  double lower = 0, upper = 0;         // chebyshev: the interval [λ/30, 1.1λ]; jacobi: ω = 1/λ = upper = lower
  std::vector<std::array<double, 2>> steps;  // (c1, c2) of one sweep
  Vector inv_diag;                     // scalar D⁻¹ (empty where D is by node blocks)
  std::vector<int> node_start;         // node blocks: node I is rows node_start[I]..node_start[I+1)
  std::vector<double> block_inv;       // node blocks: the row-major D_I⁻¹, node after node
};

struct LevelExport {
  SparseMatrix A;     // the level's operator as the V-cycle applies it (level 0: the hierarchy's
                      // copy A_F where amg.drop_tolerance dropped blocks, else the caller's A)
  SparseMatrix P, R;  // to and from the next level (0 × 0 on the coarsest)
  SmootherExport smoother;  // absent (kind "") on the coarsest level under coarse_solver = direct
};

struct HierarchyExport {
  // The resolved options the solve phase depends on: "single" | "double"; "direct" | "smoother".
  std::string precision, coarse_solver;
  int block_size = 1;
  // The coarsest level is solved directly (coarse_solver = direct: Cholesky in double of its A) or by
  // its smoother from zero (coarse_solver = smoother: one presmooth, in double).
  std::vector<LevelExport> levels;
};

// Throws xb::Error on an empty hierarchy.
HierarchyExport export_hierarchy(const Hierarchy& h);

}  // namespace xb::amg
