#include "amg_settings.hpp"

namespace xb {

const SettingTable<AmgSettings>& amg_settings() {
  using S = AmgSettings;
  static const SettingTable<S> table = {
      setting("amg.strength_threshold", "theta_s: keep |Aij| >= theta sqrt(|Aii Ajj|)", &S::strength_threshold, 0, 1),
      setting("amg.aggregation", "aggregation rule", &S::aggregation, {"standard"}),
      setting("amg.near_kernel", "near-kernel candidates: auto (ones dual, rigid primal) | ones | gs | gs_authors (6 vectors of 30 sequential forward GS sweeps from U[0,1) max|A|, smoothed P under prolongator=auto) | rigid (6 rigid-body modes, primal form only)", &S::near_kernel, {"auto", "ones", "gs", "gs_authors", "rigid"}),
      setting("amg.near_kernel_sweeps", "Gauss-Seidel sweeps on Ax=0 for near_kernel=gs", &S::near_kernel_sweeps, 0, 1e6),
      setting("amg.near_kernel_vectors", "number of gs candidate vectors", &S::near_kernel_vectors, 1, 64),
      setting("amg.near_kernel_extra", "near_kernel=rigid: this many relaxed random vectors (near_kernel_sweeps GS sweeps on Ax=0 each) appended to the 6 rigid modes", &S::near_kernel_extra, 0, 64),
      setting("amg.prolongator", "auto (tentative dual, smoothed primal) | tentative | smoothed: P = (I - omega D^-1 A) T, omega = 4/(3 lambda_max(D^-1 A))", &S::prolongator, {"auto", "tentative", "smoothed"}),
      setting("amg.nodal_strength_threshold", "theta of nodal coarsening on level 0 (block systems: primal form), on block Frobenius norms", &S::nodal_strength_threshold, 0, 1),
      setting("amg.coarse_nodal_strength_threshold", "theta of nodal coarsening on levels >= 1 (< 0: amg.nodal_strength_threshold)", &S::coarse_nodal_strength_threshold, -1, 1),
      setting("amg.min_coarsening", "block systems: a nodal aggregation with fewer nodes per aggregate than this is redone with every coupling (theta 0) on levels >= 1, then, if still below, its aggregates are aggregated again, so smoothed-P Galerkin operators do not fill in (0 = never)", &S::min_coarsening, 0, 1e6),
      setting("amg.drop_tolerance", "block systems, level 0: node blocks with |A_IJ|_F < tol sqrt(|A_II|_F |A_JJ|_F) (numerically zero couplings of the mesh pattern) are dropped from the hierarchy's copy, their norms added to the diagonal so it stays SPD (0 = keep all)", &S::drop_tolerance, 0, 1),
      setting("amg.prolongator_diagonal", "D of the smoothed prolongator: block (the node blocks: the block smoothers' D, whose lambda_max is then reused; on a scalar system the diagonal) | scalar (A's diagonal)", &S::prolongator_diagonal, {"scalar", "block"}),
      setting("amg.smoother", "auto (chebyshev dual, block_chebyshev primal) | jacobi | chebyshev | gs | block_gs (symmetric multicolour GS on node blocks) | block_jacobi | block_chebyshev (in D_block^-1 A)", &S::smoother, {"auto", "jacobi", "chebyshev", "gs", "block_gs", "block_jacobi", "block_chebyshev"}),
      setting("amg.smoother_sweeps", "pre- and post-smoothing sweeps (0 = auto: 1)", &S::smoother_sweeps, 0, 100),
      setting("amg.chebyshev_degree", "degree of the chebyshev and block_chebyshev polynomials: passes over the level's matrix per sweep (0 = auto: 3 dual, the authors'; 4 primal)", &S::chebyshev_degree, 0, 20),
      setting("amg.coarse_solver", "coarsest level: direct (Cholesky) | smoother (the level's smoother sweeps from zero, the authors')", &S::coarse_solver, {"direct", "smoother"}),
      setting("amg.jacobi_omega", "lambda_max(D^-1 A) of jacobi/chebyshev smoothers: per_level (each level's own) | level0 (level 0's on every level, the authors')", &S::jacobi_omega, {"per_level", "level0"}),
      setting("amg.setup_interval", "frames between rebuilds of aggregates and P", &S::setup_interval, 1, 1e9),
      setting("amg.max_coarse", "stop coarsening at this many rows", &S::max_coarse, 1, 1e9),
      setting("amg.max_levels", "maximum number of levels", &S::max_levels, 1, 64),
      setting("amg.precision", "storage of the V-cycle's matrices and vectors: double | single (float, as the authors ran; CG and the coarsest solve stay double; polynomial smoothers only)", &S::precision, {"double", "single"}),
  };
  return table;
}

}  // namespace xb
