#include "amg_settings.hpp"
#include "relaxation/smoothers.hpp"

#include "../../core/error.hpp"

namespace xb {

namespace {
// A row of a part's table (the smoother's, the near kernel's) as a row of AmgOptions'.
template <class Part>
SettingField<amg::AmgOptions> in_part(Part amg::AmgOptions::*part, SettingField<Part> f) {
  return rebind<amg::AmgOptions>(f, [part](amg::AmgOptions& o) -> Part& { return o.*part; });
}

// amg.smoother's choices: auto and the kinds make_smoother knows (one list).
std::vector<std::string> with_auto(const std::vector<std::string>& kinds) {
  std::vector<std::string> v{"auto"};
  v.insert(v.end(), kinds.begin(), kinds.end());
  return v;
}
}  // namespace

const SettingTable<amg::AmgOptions>& amg_settings() {
  using S = amg::AmgOptions;
  using NK = amg::NearKernelOptions;
  using SM = amg::SmootherOptions;
  // mgpbd in `run` and in `solve` (one setup and solve: no frames, no refreshes); the smoothed
  // prolongator's (auto: smoothed in the primal form, and with gs_authors candidates).
  const Scope mg = on("mgpbd").also_solve();
  const std::vector<Scope> smoothed = {Scope(mg).in("primal").where("amg.prolongator=auto|smoothed"),
                                       Scope(mg).in("dual").where("amg.prolongator=smoothed"),
                                       Scope(mg).in("dual").where("amg.prolongator=auto").where("amg.near_kernel=gs_authors")};
  static const SettingTable<S> table = {
      setting("amg.strength_threshold", "theta_s: keep |Aij| >= theta sqrt(|Aii Ajj|)", &S::strength_threshold, 0, 1)
          .applies({on("mgpbd,muelu").in("dual").also_solve(), on("hypre").also_solve()})  // muelu's primal drop tolerance is fixed (muelu.cpp)
          .instead(on("mgpbd").in("primal"), "amg.nodal_strength_threshold"),
      setting("amg.aggregation", "aggregation rule", &S::aggregation, {"standard"})
          .record_only("one rule is built (standard); runs record it"),
      in_part(&S::near_kernel, setting("amg.near_kernel", "near-kernel candidates: auto (ones dual, rigid primal) | ones | gs | gs_authors (6 vectors of 30 sequential forward GS sweeps from U[0,1) max|A|, smoothed P under prolongator=auto) | rigid (6 rigid-body modes, primal form only)", &NK::kind, {"auto", "ones", "gs", "gs_authors", "rigid"}))
          .applies({mg}),
      in_part(&S::near_kernel, setting("amg.near_kernel_sweeps", "Gauss-Seidel sweeps on Ax=0 for near_kernel=gs", &NK::sweeps, 0, 1e6))
          .applies({Scope(mg).where("amg.near_kernel=gs"), Scope(mg).in("primal").where("amg.near_kernel=auto|rigid").where("amg.near_kernel_extra>0")}),
      in_part(&S::near_kernel, setting("amg.near_kernel_vectors", "number of gs candidate vectors", &NK::vectors, 1, 64))
          .applies({Scope(mg).where("amg.near_kernel=gs")}),
      in_part(&S::near_kernel, setting("amg.near_kernel_extra", "near_kernel=rigid: this many relaxed random vectors (near_kernel_sweeps GS sweeps on Ax=0 each) appended to the 6 rigid modes", &NK::extra, 0, 64))
          .applies({Scope(mg).in("primal").where("amg.near_kernel=auto|rigid")}),
      setting("amg.prolongator", "auto (tentative dual, smoothed primal) | tentative | smoothed: P = (I - omega D^-1 A) T, omega = 4/(3 lambda_max(D^-1 A))", &S::prolongator, {"auto", "tentative", "smoothed"})
          .applies({mg}),
      setting("amg.nodal_strength_threshold", "theta of nodal coarsening on level 0 (block systems: primal form), on block Frobenius norms", &S::nodal_strength_threshold, 0, 1)
          .applies({Scope(mg).in("primal")})
          .instead(on("mgpbd").in("dual"), "amg.strength_threshold"),
      setting("amg.coarse_nodal_strength_threshold", "theta of nodal coarsening on levels >= 1 (< 0: amg.nodal_strength_threshold)", &S::coarse_nodal_strength_threshold, -1, 1)
          .applies({Scope(mg).in("primal")})
          .instead(on("mgpbd").in("dual"), "amg.strength_threshold"),
      setting("amg.min_coarsening", "block systems: a nodal aggregation with fewer nodes per aggregate than this is redone with every coupling (theta 0) on levels >= 1, then, if still below, its aggregates are aggregated again, so smoothed-P Galerkin operators do not fill in (0 = never)", &S::min_coarsening, 0, 1e6)
          .applies({Scope(mg).in("primal")}),
      setting("amg.drop_tolerance", "block systems, level 0: node blocks with |A_IJ|_F < tol sqrt(|A_II|_F |A_JJ|_F) (numerically zero couplings of the mesh pattern) are dropped from the hierarchy's copy, their norms added to the diagonal so it stays SPD (0 = keep all)", &S::drop_tolerance, 0, 1)
          .applies({Scope(mg).in("primal")}),
      setting("amg.prolongator_drop_tolerance", "smoothed P: node blocks (scalar levels: entries) with |P_IJ|_F < tol max_J |P_IJ|_F in their row node are dropped after smoothing (a sparser P: cheaper Galerkin products and coarse levels; 0 = keep all)", &S::prolongator_drop_tolerance, 0, 1)
          .applies(smoothed),
      setting("amg.coarse_refresh_interval", "refresh the coarse levels (level 0's Galerkin product and everything coarser) only on every k-th values-only refresh after a setup; in between the V-cycle keeps the last refreshed ones (1 = every refresh)", &S::coarse_refresh_interval, 1, 1e9)
          .applies({on("mgpbd")}),
      setting("amg.refresh", "a values-only setup between rebuilds: full (every level) | fine (level 0's smoother; the coarse levels lagged) | keep (nothing: the last refreshed V-cycle preconditions the new matrix); fine and keep while each solve needs at most amg.refresh_growth x the PCG iterations per decade of residual of the first solve after the last full refresh", &S::refresh, {"full", "fine", "keep"})
          .applies({on("mgpbd")}),
      setting("amg.refresh_growth", "amg.refresh = fine | keep: a full refresh once a solve needs more than this factor x the PCG iterations per decade of the first solve after the last full refresh", &S::refresh_growth, 1, 1e9)
          .applies({on("mgpbd").where("amg.refresh=fine|keep")}),
      setting("amg.prolongator_diagonal", "D of the smoothed prolongator: block (the node blocks: the block smoothers' D, whose lambda_max is then reused; on a scalar system the diagonal) | scalar (A's diagonal)", &S::prolongator_diagonal, {"scalar", "block"})
          .applies({Scope(mg).in("primal").where("amg.prolongator!=tentative")}),
      in_part(&S::smoother, setting("amg.smoother", "auto (chebyshev dual, block_chebyshev primal) | jacobi | chebyshev | gs | block_gs (symmetric multicolour GS on node blocks) | block_jacobi | block_chebyshev (in D_block^-1 A)", &SM::kind, with_auto(amg::smoother_kinds())))
          .applies({mg}),
      in_part(&S::smoother, setting("amg.smoother_sweeps", "pre- and post-smoothing sweeps (0 = auto: 1)", &SM::sweeps, 0, 100))
          .applies({mg}),
      in_part(&S::smoother, setting("amg.chebyshev_degree", "degree of the chebyshev and block_chebyshev polynomials: passes over the level's matrix per sweep (0 = auto: 3 dual, the authors'; 4 primal)", &SM::degree, 0, 20))
          .applies({Scope(mg).where("amg.smoother=auto|chebyshev|block_chebyshev")}),
      setting("amg.coarse_solver", "coarsest level: direct (Cholesky) | smoother (the level's smoother sweeps from zero, the authors')", &S::coarse_solver, {"direct", "smoother"})
          .applies({mg}),
      setting("amg.jacobi_omega", "lambda_max(D^-1 A) of jacobi/chebyshev smoothers: per_level (each level's own) | level0 (level 0's on every level, the authors')", &S::jacobi_omega, {"per_level", "level0"})
          .applies({Scope(mg).where("amg.smoother=jacobi|chebyshev"), Scope(mg).in("dual").where("amg.smoother=auto")}),
      setting("amg.setup_interval", "frames between rebuilds of aggregates and P", &S::setup_interval, 1, 1e9)
          .applies({on("mgpbd,muelu").where("frames>1"), on("hypre").where("frames>1").where("hypre.reuse=hierarchy")}),
      setting("amg.max_coarse", "stop coarsening at this many rows", &S::max_coarse, 1, 1e9)
          .applies({mg}),
      setting("amg.max_levels", "maximum number of levels", &S::max_levels, 1, 64)
          .applies({mg, on("muelu").also_solve()}),
      setting("amg.precision", "storage of the V-cycle's matrices and vectors: auto (single with the polynomial smoothers, double with gs / block_gs) | double | single (float, as the authors ran; CG and the coarsest solve stay double; polynomial smoothers only)", &S::precision, {"auto", "double", "single"})
          .applies({mg}),
  };
  return table;
}

}  // namespace xb

namespace xb::amg {

AmgOptions resolve_options(const AmgOptions& opt, const MatrixInfo& info) {
  check_settings(amg_settings(), opt, "mgpbd");
  if (info.block_size < 1) throw Error("mgpbd: block size must be >= 1");
  AmgOptions o = opt;
  const bool block = info.block_size > 1;
  if (o.near_kernel.kind == "auto") o.near_kernel.kind = block && info.near_kernel ? "rigid" : "ones";
  if (o.near_kernel.kind == "rigid" && !info.near_kernel)
    throw Error("amg.near_kernel=rigid needs the rigid-body modes of the primal form (form=primal); this system has none");
  if (o.prolongator == "auto") o.prolongator = block || o.near_kernel.kind == "gs_authors" ? "smoothed" : "tentative";
  if (o.smoother.kind == "auto") o.smoother.kind = block ? kBlockSmoother : "chebyshev";
  if (o.jacobi_omega == "level0" && o.smoother.kind != "jacobi" && o.smoother.kind != "chebyshev")
    throw Error("amg.jacobi_omega=level0 needs amg.smoother jacobi or chebyshev (the smoother is " + o.smoother.kind + ")");
  if (o.smoother.sweeps == 0) o.smoother.sweeps = block ? kBlockSmootherSweeps : 1;
  if (o.smoother.degree == 0) o.smoother.degree = block ? kBlockChebyshevDegree : 3;
  const bool gauss_seidel = o.smoother.kind == "gs" || o.smoother.kind == "block_gs";
  if (o.precision == "auto") o.precision = gauss_seidel ? "double" : "single";
  if (o.precision == "single" && gauss_seidel)
    throw Error("amg.precision=single runs the polynomial smoothers (jacobi, chebyshev, block_jacobi, block_chebyshev), not amg.smoother=" +
                o.smoother.kind);
  return o;
}

}  // namespace xb::amg
