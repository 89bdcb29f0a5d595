// Near-kernel candidates B (n × k): the vectors the tentative prolongator must reproduce.
//  ones: B = 1 (plain unsmoothed aggregation, the authors' released code).
//  gs:   the paper's: `sweeps` multicolour Gauss–Seidel sweeps on A x = 0 from a random start
//        (seeded, so a setup is reproducible), `vectors` of them; each column scaled to unit norm.
#pragma once

#include "../../problems/sparse.hpp"
#include "../coloring.hpp"

#include <Eigen/Dense>
#include <string>

namespace xb::amg {

struct NearKernelOptions {
  std::string kind = "ones";  // ones | gs
  int sweeps = 20;
  int vectors = 1;
  unsigned seed = 1;
};

// `coloring` (of A's pattern) may be passed to reuse one; otherwise one is computed for gs.
// Throws xb::Error naming amg.near_kernel for an unknown kind.
Eigen::MatrixXd near_kernel_candidates(const SparseMatrix& A, const NearKernelOptions& opt,
                                       const Coloring* coloring = nullptr);

}  // namespace xb::amg
