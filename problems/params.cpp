#include "params.hpp"

#include "error.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace xb {

namespace {
using T = ParamField::Type;
constexpr double inf = 1e300;

std::vector<ParamField> make_fields() {
  std::vector<ParamField> f = {
      {"scene", T::String, "scene builder name", &Params::scene, -inf, inf, {}},
      {"mesh", T::String, "mesh: '' (generator), 'bunny:12k', or a .msh/.mesh/.ele/.node path", &Params::mesh, -inf, inf, {}},
      {"resolution", T::Int, "cells per side of generated meshes", &Params::resolution, 1, 4096, {}},
      {"aspect", T::Int, "bar length in cells = aspect * resolution", &Params::aspect, 1, 1024, {}},
      {"size", T::Double, "m, cloth side / bar cross-section side", &Params::size, 1e-6, inf, {}},
      {"frames", T::Int, "frames to simulate", &Params::frames, 1, 1e9, {}},
      {"substeps", T::Int, "substeps per frame", &Params::substeps, 1, 1e6, {}},
      {"dt", T::Double, "s, frame time step", &Params::dt, 1e-300, inf, {}},
      {"gravity", T::Double, "m/s^2 along y", &Params::gravity, -inf, inf, {}},
      {"particle_mass", T::Double, "kg per particle", &Params::particle_mass, 1e-300, inf, {}},
      {"compliance", T::Double, "m/N, distance-constraint compliance (0 = rigid)", &Params::compliance, 0, inf, {}},
      {"stiffness", T::Double, "Pa, ARAP shear modulus mu of tets (alpha = 1/(mu V))", &Params::stiffness, 1e-300, inf, {}},
      {"prestretch", T::Double, "initial stretch of a generated bar along its length (1 = rest shape)", &Params::prestretch, 0.1, 10, {}},
      {"twist", T::Double, "rad, twist_bar: initial twist about the long axis, end to end", &Params::twist, -1e3, 1e3, {}},
      {"mass_ratio", T::Double, "heaviest/lightest particle mass, graded by index as i^2 (1 = uniform)", &Params::mass_ratio, 1, 1e300, {}},
      {"mesh_height", T::Double, "m, mesh scenes (squash, twist_bar, cantilever, ball_drop): scale the mesh uniformly so its y extent is this (0 = as the mesh is)", &Params::mesh_height, 0, inf, {}},
      {"init", T::String, "squash's start: none (collapsed to min y) | enlarge (the rest mesh x1.5 about its centroid, the authors' enlarge start)", &Params::init, 0, 0, {"none", "enlarge"}},
      {"variant", T::String, "extreme case: none | rigid | mu1e12 | mass_ratio_1e4 | dt_30hz | near_degenerate (sets the keys it implies)", &Params::variant, 0, 0, {"none", "rigid", "mu1e12", "mass_ratio_1e4", "dt_30hz", "near_degenerate"}},
      {"max_iterations", T::Int, "outer iterations per substep", &Params::max_iterations, 1, 1e9, {}},
      {"rtol", T::Double, "outer stop: dual residual relative to iteration 0", &Params::rtol, 0, inf, {}},
      {"atol", T::Double, "outer stop: absolute dual residual", &Params::atol, 0, inf, {}},
      {"omega", T::Double, "global step size x += omega M^-1 grad C^T dlambda", &Params::omega, 1e-300, 2, {}},
      {"residual_metric", T::String, "dual residual of the stop test: true (|C(x_k) + alpha~ lambda_k|) | authors (|C(x~) + alpha~ lambda_k| local, |C(x_k-1) + alpha~ lambda_k| global)", &Params::residual_metric, 0, 0, {"true", "authors"}},
      {"step", T::String, "global step: fixed (x += omega M^-1 grad C^T dlambda) | line_search (backtracking t = 1, 1/2, ... on the dual residual, x += t dx, lambda += t dlambda)", &Params::step, 0, 0, {"fixed", "line_search"}},
      {"xpbd.position_relaxation", T::Double, "xpbd-authors: x += this * M^-1 grad C^T dlambda (lambda takes the full dlambda)", &Params::position_relaxation, 1e-300, 2, {}},
      {"xpbd.jacobi_relaxation", T::Double, "xpbd-jacobi relaxation of dlambda and dx (0 = 1/max constraints per particle)", &Params::jacobi_relaxation, 0, 2, {}},
      {"threads", T::Int, "OpenMP threads (0 = default)", &Params::threads, 0, 4096, {}},
      {"seed", T::Int, "random seed", &Params::seed, 0, 2147483647.0, {}},
      {"form", T::String, "linear step of global methods: dual (A dlambda = b) | primal (K dx = J^T alpha~^-1 b, every alpha~ > 0) | auto (primal when every alpha~ > 0)", &Params::form, 0, 0, {"dual", "primal", "auto"}},
      {"linear.tol", T::Double, "linear solve: |r|_2 <= tol |b|_2", &Params::linear_tol, 0, 1, {}},
      {"linear.max_iterations", T::Int, "linear solve iteration limit", &Params::linear_max_iterations, 1, 1e9, {}},
      {"amg.strength_threshold", T::Double, "theta_s: keep |Aij| >= theta sqrt(|Aii Ajj|)", &Params::amg_strength_threshold, 0, 1, {}},
      {"amg.aggregation", T::String, "aggregation rule", &Params::amg_aggregation, 0, 0, {"standard"}},
      {"amg.near_kernel", T::String, "near-kernel candidates: auto (ones dual, rigid primal) | ones | gs | rigid (6 rigid-body modes, primal form only)", &Params::amg_near_kernel, 0, 0, {"auto", "ones", "gs", "rigid"}},
      {"amg.near_kernel_sweeps", T::Int, "Gauss-Seidel sweeps on Ax=0 for near_kernel=gs", &Params::amg_near_kernel_sweeps, 0, 1e6, {}},
      {"amg.near_kernel_vectors", T::Int, "number of gs candidate vectors", &Params::amg_near_kernel_vectors, 1, 64, {}},
      {"amg.prolongator", T::String, "auto (tentative dual, smoothed primal) | tentative | smoothed: P = (I - omega D^-1 A) T, omega = 4/(3 lambda_max(D^-1 A))", &Params::amg_prolongator, 0, 0, {"auto", "tentative", "smoothed"}},
      {"amg.nodal_strength_threshold", T::Double, "theta of nodal coarsening on level 0 (block systems: primal form), on block Frobenius norms", &Params::amg_nodal_strength_threshold, 0, 1, {}},
      {"amg.coarse_nodal_strength_threshold", T::Double, "theta of nodal coarsening on levels >= 1 (< 0: amg.nodal_strength_threshold)", &Params::amg_coarse_nodal_strength_threshold, -1, 1, {}},
      {"amg.prolongator_diagonal", T::String, "D of the smoothed prolongator: scalar (A's diagonal) | block (node blocks)", &Params::amg_prolongator_diagonal, 0, 0, {"scalar", "block"}},
      {"amg.smoother", T::String, "auto (chebyshev dual, block_chebyshev primal) | jacobi | chebyshev | gs | block_gs (symmetric multicolour GS on node blocks) | block_jacobi | block_chebyshev (in D_block^-1 A)", &Params::amg_smoother, 0, 0, {"auto", "jacobi", "chebyshev", "gs", "block_gs", "block_jacobi", "block_chebyshev"}},
      {"amg.smoother_sweeps", T::Int, "pre- and post-smoothing sweeps (0 = auto: 1 dual, 2 primal)", &Params::amg_smoother_sweeps, 0, 100, {}},
      {"amg.setup_interval", T::Int, "frames between rebuilds of aggregates and P", &Params::amg_setup_interval, 1, 1e9, {}},
      {"amg.max_coarse", T::Int, "stop coarsening at this many rows", &Params::amg_max_coarse, 1, 1e9, {}},
      {"amg.max_levels", T::Int, "maximum number of levels", &Params::amg_max_levels, 1, 64, {}},
      {"amg.precision", T::String, "storage of the V-cycle's matrices and vectors: double | single (float, as the authors ran; CG and the coarsest solve stay double; polynomial smoothers only)", &Params::amg_precision, 0, 0, {"double", "single"}},
      {"hypre.coarsening", T::String, "BoomerAMG coarsening", &Params::hypre_coarsening, 0, 0, {"HMIS", "PMIS", "Falgout"}},
      {"hypre.interpolation", T::String, "BoomerAMG interpolation", &Params::hypre_interpolation, 0, 0, {"ext+i", "classical", "direct", "multipass"}},
      {"hypre.relaxation", T::String, "BoomerAMG relaxation", &Params::hypre_relaxation, 0, 0, {"l1-jacobi", "jacobi", "hgs", "l1-gs", "chebyshev"}},
      {"hypre.aggressive_levels", T::Int, "levels of aggressive coarsening", &Params::hypre_aggressive_levels, 0, 25, {}},
      {"hypre.max_levels", T::Int, "BoomerAMG maximum levels", &Params::hypre_max_levels, 1, 64, {}},
      {"hypre.reuse", T::String, "Values setups: none (full BoomerAMG setup) | hierarchy (keep the last one until a rebuild every amg.setup_interval frames)", &Params::hypre_reuse, 0, 0, {"none", "hierarchy"}},
      {"muelu.algorithm", T::String, "auto (unsmoothed dual, sa primal) | unsmoothed | sa (smoothed aggregation)", &Params::muelu_algorithm, 0, 0, {"auto", "unsmoothed", "sa"}},
      {"muelu.smoother", T::String, "chebyshev | jacobi | gs | sgs", &Params::muelu_smoother, 0, 0, {"chebyshev", "jacobi", "gs", "sgs"}},
      {"muelu.smoother_sweeps", T::Int, "smoother sweeps", &Params::muelu_smoother_sweeps, 1, 100, {}},
      {"muelu.coarse_size", T::Int, "coarse size", &Params::muelu_coarse_size, 1, 1e9, {}},
      {"muelu.reuse", T::String, "Values setups: MueLu reuse: type none | tP | RP (full rebuild every amg.setup_interval frames)", &Params::muelu_reuse, 0, 0, {"none", "tP", "RP"}},
  };
  return f;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}
}  // namespace

const std::vector<ParamField>& param_fields() {
  static const std::vector<ParamField> fields = make_fields();
  return fields;
}

const ParamField* find_param(const std::string& key) {
  for (const auto& f : param_fields())
    if (f.key == key) return &f;
  return nullptr;
}

void set_param(Params& p, const std::string& key, const std::string& value, const std::string& where) {
  const ParamField* f = find_param(key);
  if (!f) {
    std::vector<std::string> keys;
    for (const auto& g : param_fields()) keys.push_back(g.key);
    throw Error(where + ": unknown parameter '" + key + "' (valid: " + join(keys) + ")");
  }
  auto bad = [&](const std::string& what) {
    return Error(where + ": parameter '" + key + "' = '" + value + "': " + what);
  };
  if (f->type == T::String) {
    if (!f->choices.empty() && std::find(f->choices.begin(), f->choices.end(), value) == f->choices.end())
      throw bad("must be one of " + join(f->choices));
    p.*std::get<std::string Params::*>(f->member) = value;
    if (key == "variant") apply_variant_keys(p);  // a variant sets the keys it implies, where it is set
    return;
  }
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size() || errno == ERANGE || !std::isfinite(v))
    throw bad("not a finite number");
  if (v < f->min || v > f->max) {
    std::ostringstream os;
    os << "out of range [" << f->min << ", " << f->max << "]";
    throw bad(os.str());
  }
  if (f->type == T::Int) {
    if (v != std::floor(v)) throw bad("must be an integer");
    p.*std::get<int Params::*>(f->member) = static_cast<int>(v);
  } else {
    p.*std::get<double Params::*>(f->member) = v;
  }
}

std::string param_to_string(const Params& p, const ParamField& f) {
  std::ostringstream os;
  os.precision(17);
  std::visit([&](auto m) { os << p.*m; }, f.member);
  return os.str();
}

ParamValue param_value(const Params& p, const ParamField& f) {
  switch (f.type) {
    case T::Int: return static_cast<long long>(p.*std::get<int Params::*>(f.member));
    case T::Double: return p.*std::get<double Params::*>(f.member);
    default: return p.*std::get<std::string Params::*>(f.member);
  }
}

void apply_variant_keys(Params& p) {
  // What each extreme case changes in the parameters; rigid and near_degenerate also act on the
  // built Problem (problems/scene.cpp: apply_variant_to_problem / the mesh builders).
  if (p.variant == "rigid") p.compliance = 0;
  else if (p.variant == "mu1e12") p.stiffness = 1e12;
  else if (p.variant == "mass_ratio_1e4") p.mass_ratio = 1e4;
  else if (p.variant == "dt_30hz") p.dt = 1.0 / 30.0;
}

void validate(const Params& p) {
  // Bounds are checked per key in set_param; these are the checks across keys or of defaults
  // that a scene file could have left inconsistent.
  if (!(p.dt > 0)) throw Error("parameter 'dt' must be > 0");
  if (p.frames < 1) throw Error("parameter 'frames' must be >= 1");
  if (p.max_iterations < 1) throw Error("parameter 'max_iterations' must be >= 1");
}

}  // namespace xb
