// The one parameter struct of xpbd-bench. Its defaults, the scene TOML reader, the CLI's
// --set key=value and the HDF5 attributes of a run all go through the field table below,
// so a key is spelled the same everywhere. Units: seconds, kg, m, Pa, m/N.
#pragma once

#include <string>
#include <variant>
#include <vector>

namespace xb {

struct Params {
  // --- scene ---
  std::string scene = "cloth_hang";  // the scene builder (see problems/scene.cpp)
  std::string mesh = "";             // "" = the builder's generator; "bunny:12k"; or a mesh path
  int resolution = 32;               // cells per side for generated meshes
  int aspect = 4;                    // bar length in cells = aspect * resolution
  double size = 1.0;                 // m: cloth side length / bar cross-section side
  int frames = 1;
  int substeps = 1;                  // substeps per frame
  double dt = 3e-3;                  // s, frame time step (substep = dt / substeps)
  double gravity = -9.8;             // m/s², along y
  double particle_mass = 1.0;        // kg per particle
  double compliance = 1e-8;          // m/N, distance constraints
  double stiffness = 1e6;            // Pa, μ of the tet ARAP constraint (α = 1/(μ V_rest))
  double prestretch = 1.0;           // initial stretch of generated bars along their length (1 = at rest)
  double twist = 0;                  // rad: twist_bar's initial twist of the bar about its long axis, end to end
  double mass_ratio = 1;             // heaviest/lightest particle: mass_i = particle_mass·(1 + (ratio−1)(i/(n−1))²)
  double mesh_height = 0;            // m: mesh scenes scale the mesh so its y extent is this (0 = as the file is)
  std::string init = "none";         // squash start: none (collapsed) | enlarge (rest mesh x1.5 about its centroid)
  std::string variant = "none";      // extreme case (problems/scene.hpp: apply_variant); setting it also sets the keys it implies
  // --- outer (nonlinear) loop ---
  int max_iterations = 100;          // outer iterations per substep
  double rtol = 1e-6;                // stop when ‖C+α̃λ‖ ≤ rtol·(its value at iteration 0)
  double atol = 1e-12;               // or when ‖C+α̃λ‖ ≤ atol
  double omega = 1.0;                // global step x += ω M⁻¹∇CᵀΔλ (paper's code: 0.1 soft, 0.25 cloth)
  // Which dual residual the stop test (rtol/atol) reads: true ‖C(x_k) + α̃λ_k‖ | authors (the
  // quantity the authors' code logs, harness/sim/stepper.hpp: IterationLog::authors_dual_residual).
  std::string residual_metric = "true";
  // Global step: fixed (x += ω M⁻¹∇CᵀΔλ, λ += Δλ) | line_search (the authors' backtracking on the
  // dual residual, harness/sim/line_search.hpp; ω unused).
  std::string step = "fixed";
  double position_relaxation = 0.1;  // xpbd-authors: x += this·M⁻¹∇CᵀΔλ while λ takes the full Δλ
  double jacobi_relaxation = 0;      // xpbd-jacobi: λ += ωJ·Δλ, x += ωJ·M⁻¹∇CᵀΔλ; 0 = 1/(most constraints on one particle)
  int threads = 0;                   // OpenMP threads, 0 = OpenMP's default
  int seed = 1;
  // --- linear solvers ---
  // The form of every global method's linear step: dual (A Δλ = b) | primal (K Δx = Jᵀα̃⁻¹b,
  // then Δλ = α̃⁻¹(b − JΔx); needs every α̃ > 0) | auto (primal when every α̃ > 0, else dual).
  std::string form = "dual";
  double linear_tol = 1e-8;          // ‖r‖₂ ≤ tol·‖b‖₂
  int linear_max_iterations = 1000;
  // --- in-house MGPBD AMG ---
  double amg_strength_threshold = 0.25;
  std::string amg_aggregation = "standard";
  std::string amg_near_kernel = "auto";  // auto (ones dual, rigid primal) | ones | gs | rigid
  int amg_near_kernel_sweeps = 20;
  int amg_near_kernel_vectors = 1;
  std::string amg_prolongator = "auto";  // auto (tentative dual, smoothed primal) | tentative | smoothed
  double amg_nodal_strength_threshold = 0.0;         // block systems (primal K), level 0
  double amg_coarse_nodal_strength_threshold = 0.1;  // levels >= 1 (< 0: the level-0 value)
  std::string amg_prolongator_diagonal = "scalar";   // D of the smoothed P: scalar | block
  std::string amg_smoother = "auto";  // auto (chebyshev dual, block_chebyshev primal) | jacobi | chebyshev | gs | block_gs | block_jacobi | block_chebyshev
  int amg_smoother_sweeps = 0;        // 0: auto (1 dual, 2 primal)
  int amg_setup_interval = 20;       // frames between rebuilds of aggregates and P
  int amg_max_coarse = 400;
  int amg_max_levels = 10;
  std::string amg_precision = "double";  // storage of the V-cycle: double | single (float matrices and vectors; CG stays double)
  // --- hypre BoomerAMG ---
  std::string hypre_coarsening = "HMIS";    // HMIS | PMIS | Falgout
  std::string hypre_interpolation = "ext+i";  // ext+i | classical | direct | multipass
  std::string hypre_relaxation = "l1-jacobi";  // l1-jacobi | jacobi | hgs | l1-gs | chebyshev
  int hypre_aggressive_levels = 0;
  int hypre_max_levels = 25;
  std::string hypre_reuse = "none";  // none | hierarchy (keep the last hierarchy for Values setups)
  // --- Trilinos MueLu ---
  std::string muelu_algorithm = "auto";  // auto (unsmoothed dual, sa primal) | unsmoothed | sa
  std::string muelu_smoother = "chebyshev";  // chebyshev | jacobi | gs | sgs
  int muelu_smoother_sweeps = 1;
  int muelu_coarse_size = 400;
  std::string muelu_reuse = "RP";  // none | tP | RP: MueLu "reuse: type" for Values setups
  // The profile the parameters came from ("" = none; harness/cli/profile.hpp). Not a key of the field
  // table (a profile is a set of keys, not one): simulation runs record it as the attribute `profile`.
  std::string profile;
};

// One entry of the field table.
struct ParamField {
  std::string key;          // e.g. "amg.strength_threshold"
  enum class Type { Int, Double, String } type;
  std::string doc;          // one line, with units
  // Accessors into a Params (so the table has one definition per key).
  std::variant<int Params::*, double Params::*, std::string Params::*> member;
  double min = -1e300, max = 1e300;  // inclusive bounds for numbers
  std::vector<std::string> choices;  // allowed strings, empty = any
};

const std::vector<ParamField>& param_fields();
const ParamField* find_param(const std::string& key);

// Set one key from text, validating type, bounds and choices. `where` names the source
// ("--set", "scene.toml:12") for the error message. Throws xb::Error.
void set_param(Params& p, const std::string& key, const std::string& value, const std::string& where);

// A key's value as text (for tables, JSON) and as a typed value (for HDF5).
std::string param_to_string(const Params& p, const ParamField& f);
using ParamValue = std::variant<long long, double, std::string>;
ParamValue param_value(const Params& p, const ParamField& f);

// Sets the keys p.variant implies (rigid: compliance 0; mu1e12: stiffness 1e12;
// mass_ratio_1e4: mass_ratio 1e4; dt_30hz: dt 1/30 s). Called by set_param("variant").
void apply_variant_keys(Params& p);

// Cross-field checks (e.g. dt > 0); throws xb::Error naming the key.
void validate(const Params& p);

}  // namespace xb
