// Near-kernel candidates B (n × k): the vectors the tentative prolongator must reproduce.
//  ones: B = 1 (plain unsmoothed aggregation, the authors' released code); on a block system
//        (b unknowns per node) the b unit components per node (on K: the 3 translations).
//  rigid: the caller's basis (the primal form's 6 rigid-body modes), copied, with `extra` gs
//        vectors appended.
//  gs:   the paper's: `sweeps` multicolour Gauss–Seidel sweeps on A x = 0 from a random start
//        (seeded, so a setup is reproducible), `vectors` of them; each column scaled to unit norm.
//  gs_authors: the authors' recipe, whatever sweeps/vectors say: 6 vectors, each 30 sequential
//        forward Gauss–Seidel sweeps (row order, as pyamg's) on A x = 0 from U[0,1)·max|A|.
#pragma once

#include "../../core/sparse.hpp"
#include "../coloring.hpp"

#include <Eigen/Dense>
#include <string>

namespace xb::amg {

struct NearKernelOptions {
  std::string kind = "ones";  // ones | gs | gs_authors | rigid (auto is resolved by the hierarchy)
  int sweeps = 20;
  int vectors = 1;
  int extra = 0;  // rigid: this many relaxed random vectors appended to the caller's basis
  unsigned seed = 1;
};

// `coloring` (of A's pattern) may be passed to reuse one; otherwise one is computed for gs.
// `given`: the caller's near-kernel basis (rigid needs it). Throws xb::Error naming
// amg.near_kernel for an unknown kind, for rigid without `given` or with the wrong row count.
Eigen::MatrixXd near_kernel_candidates(const SparseMatrix& A, const NearKernelOptions& opt,
                                       const Coloring* coloring = nullptr, int block_size = 1,
                                       const Eigen::MatrixXd* given = nullptr);

// `count` vectors, each `sweeps` forward multicolour Gauss–Seidel sweeps on A x = 0 from a seeded
// random start, scaled to unit norm (the gs candidates).
Eigen::MatrixXd relaxed_random_vectors(const SparseMatrix& A, int count, int sweeps, unsigned seed,
                                       const Coloring* coloring = nullptr);

// The gs_authors candidates (kGsAuthorsVectors × kGsAuthorsSweeps), each scaled to unit norm.
inline constexpr int kGsAuthorsVectors = 6;
inline constexpr int kGsAuthorsSweeps = 30;
Eigen::MatrixXd gs_authors_vectors(const SparseMatrix& A, unsigned seed);

}  // namespace xb::amg
