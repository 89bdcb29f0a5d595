// The in-house AMG's settings (mgpbd): one struct, AmgOptions, with the amg.* keys' defaults, read
// by the hierarchy and its parts as they are (the smoother and near-kernel parts are their own
// option structs, pointed at by the same table). amg.setup_interval also paces the lazy setup of
// hypre and MueLu (solvers/setup_policy.hpp).
// resolve_options turns the "auto" and 0 (= auto) values into what they mean for a matrix; the
// hierarchy does that once per setup (Hierarchy::configure).
#pragma once

#include "../../core/settings.hpp"
#include "near_kernel.hpp"
#include "relaxation/smoothers.hpp"

#include <Eigen/Dense>
#include <string>

namespace xb::amg {

struct AmgOptions {
  double strength_threshold = 0.25;   // θ_s of scalar (dual) coarsening
  std::string aggregation = "standard";
  // kind auto: rigid on a block system with a basis, else ones. The seed is SolverSettings::seed.
  NearKernelOptions near_kernel{.kind = "auto"};
  std::string prolongator = "auto";   // auto (smoothed on block systems or gs_authors, else tentative) | tentative | smoothed
  // θ_s of nodal coarsening (block systems, on block Frobenius norms). 0 keeps every coupling, as
  // pyamg's smoothed aggregation does by default: 0.25 isolates half the cloth's particles (an
  // off-diagonal block of K is about a quarter of its diagonal block there) and shrinks the bar's
  // aggregates to ~4 particles (operator complexity 7.7).
  double nodal_strength_threshold = 0.0;
  // θ_s of nodal coarsening on levels ≥ 1 (< 0: nodal_strength_threshold). Galerkin operators of
  // a smoothed P couple neighbours of neighbours, so θ = 0 there (pyamg's) coarsens level 1 by
  // ~80× on squash bunny:270k (22,458 → 288 rows); 0.1 made a 2,832-row level 2 with 929
  // non-zeros per row, whose Galerkin products were half the refresh (operator complexity 2.02
  // against 1.67), for the same 16 PCG iterations to a dual 1e-1 (docs/mgpbd.md).
  double coarse_nodal_strength_threshold = 0.0;
  // A nodal aggregation with fewer than this many nodes per aggregate coarsens too slowly: a
  // smoothed P then fills the next operator in. On levels ≥ 1 it is first redone at θ = 0 (the
  // stretched bar, bar_hang r16, went 792 → 286 nodes at θ = 0.1, its level 2 43% dense); if it
  // is still below (on any level: couplings along lines only, as the filtered bar's), its
  // aggregates are aggregated again on the graph of their couplings until it is not. 0 = never.
  double min_coarsening = 4;
  // Block systems, level 0: node blocks below this fraction of their diagonals' geometric mean
  // are dropped, their norms lumped onto the diagonal (zero_filter.hpp). Round-off zeros are
  // ≤ 1e-14 there (bar_hang); the smallest real coupling on the captured systems is 3e-6 (squash
  // bunny:50k). 0 = keep every block.
  double drop_tolerance = 1e-10;
  // Smoothed P: node blocks (scalar levels: entries) below this fraction of the largest block
  // of their row node are dropped after the smoothing (ML/MueLu's filtered prolongator): a
  // sparser P makes both the Galerkin products and the coarse operator cheaper. 0 = keep all.
  double prolongator_drop_tolerance = 0.0;
  // Refresh the coarse levels (level 0's Galerkin product and all below it) only on every k-th
  // refresh after a setup; between them the V-cycle keeps the last refreshed coarse levels (a
  // lagged but still SPD preconditioner) and level 0's own smoother is refreshed. 1 = always.
  int coarse_refresh_interval = 1;
  // What a values-only setup between rebuilds does (refresh_rule.hpp): full (every level, as
  // above) | fine (level 0's smoother; the coarse levels lagged) | keep (nothing), the last two
  // while a solve needs at most refresh_growth × the PCG iterations per decade of residual of the
  // first solve after the last full refresh. full under XPBD (its K moves too much between outer
  // iterations: coarse_refresh_interval = 2 doubled the PCG count); the newton profile's is
  // measured in docs/mgpbd.md.
  std::string refresh = "full";
  double refresh_growth = 1.5;
  // D of the smoothed P: block | scalar. Block (a scalar layout's blocks are its diagonal): the
  // same or fewer iterations than the scalar D on the captured primal systems (squash 29 against
  // 31), and the block smoother's λ_max(D⁻¹A) serves P too (one Lanczos per level, not two).
  std::string prolongator_diagonal = "block";
  // kind auto: kBlockSmoother on a block system, else chebyshev; sweeps 0: kBlockSmootherSweeps
  // on a block system, else 1; degree 0: kBlockChebyshevDegree on a block system, else 3.
  SmootherOptions smoother{.kind = "auto", .sweeps = 0, .degree = 0};
  int setup_interval = 20;            // frames between rebuilds of aggregates and P (SetupPolicy)
  int max_coarse = 400;
  int max_levels = 10;
  std::string coarse_solver = "direct";    // direct (Cholesky) | smoother (the level's smoother from zero)
  std::string jacobi_omega = "per_level";  // per_level | level0 (level 0's λ_max(D⁻¹A) on every level)
  // Storage of the V-cycle: "double", or "single" (float copies of every level's A, P, R and of
  // its polynomial smoother, made at setup and refresh; CG and the coarsest solve stay double).
  // auto: single with the polynomial smoothers, double with the Gauss–Seidel kinds (which have
  // no float form). The race chose single: the V-cycle is bandwidth-bound, and at 315K tets the
  // float one made a frame 25-29% faster for the same iterations (docs/race.md).
  std::string precision = "auto";
};

// What amg.smoother = auto, amg.smoother_sweeps = 0 and amg.chebyshev_degree = 0 take on block
// systems (the primal form): one sweep of a degree-4 Chebyshev in D_block⁻¹A. Per decade of
// residual it is cheaper than degree 3 × 2 on every captured system (scripts/smoother_table.py,
// docs/mgpbd.md: four passes before and after instead of six, for 0–30% more iterations);
// degree 3 × 1 is cheaper still but leaves the stretched bar above a fifth of dual jacobi-pcg's
// iterations. Block Gauss–Seidel costs about twice as much per decade there.
inline constexpr const char* kBlockSmoother = "block_chebyshev";
inline constexpr int kBlockSmootherSweeps = 1;
inline constexpr int kBlockChebyshevDegree = 4;

// What the caller knows about the matrix beyond its entries (SetupContext's fields).
struct MatrixInfo {
  int block_size = 1;                          // unknowns per node, node-major
  const Eigen::MatrixXd* near_kernel = nullptr;  // n × k basis (rigid-body modes), setup only
};

// The options with "auto" resolved for this matrix (near_kernel = gs_authors makes an auto
// prolongator smoothed, as the authors hand their candidates to smoothed aggregation). Throws
// xb::Error for a value the amg.* table refuses (its choices and bounds, its message), for
// near_kernel = rigid without a basis, jacobi_omega = level0 with a smoother other than jacobi or
// chebyshev, and precision = single with a Gauss–Seidel smoother.
AmgOptions resolve_options(const AmgOptions& opt, const MatrixInfo& info);

}  // namespace xb::amg

namespace xb {
// The amg.* keys, each pointing at its member of AmgOptions.
const SettingTable<amg::AmgOptions>& amg_settings();
}  // namespace xb
