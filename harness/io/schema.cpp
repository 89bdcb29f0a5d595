#include "schema.hpp"

#include "../params.hpp"

#include <sstream>
#include <stdexcept>

namespace xb {

namespace {
// Names sharing a level and a type.
struct SchemaGroup {
  std::string level, type;
  std::vector<std::string> names;
};
std::vector<SchemaName> expand(const std::vector<SchemaGroup>& groups) {
  std::vector<SchemaName> out;
  for (const auto& g : groups)
    for (const auto& n : g.names) out.push_back({n, g.level, g.type});
  return out;
}
}  // namespace

const ResultsSchema& results_schema() {
  // Attributes: every run's (what, how it ended, provenance, solver statistics), then simulation
  // runs' (summary, local-method details, the reference, sweeps), then linear runs' (solve).
  static const ResultsSchema s = {
      expand({
          {"any", "string", {"level", "scene", "solver", "form_used", "status", "message", "git_sha", "machine", "created", "omp_wait_policy", "omp_spin_count"}},
          {"any", "int", {"omp_threads", "cpu_count", "blas_threads"}},
          {"any", "float", {"load_average", "levels", "operator_complexity", "grid_complexity", "factor_nnz", "factor_flops", "factorisations", "factorise_time_total", "analyse_time_total", "lagged_setups", "refactorisations_in_solve", "mpi_ranks", "setup_count", "refresh_count", "reuse_count", "setup_full", "setup_reused", "setup_time_total", "refresh_time_total", "single_precision", "primal_rows", "primal_nonzeros"}},
          {"any", "number", {"rows"}},
          {"simulation", "string", {"profile", "reference_method", "reference_file", "sweep_spec", "sweep_description", "sweep_params", "sweep_point", "sweep_key", "sweep_base"}},
          {"simulation", "int", {"outer_iterations", "substeps_total", "substeps_converged", "reference", "reference_substeps_unconverged", "reference_substeps_uncertified", "sweep_index", "sweep_repeat"}},
          {"simulation", "float", {"final_dual_residual", "relative_dual_residual", "final_authors_dual_residual", "wall_time", "nonzeros", "particles", "colors", "jacobi_relaxation_used", "authors_skipped_last_sweep", "time_budget", "reference_dual_residual", "reference_time", "final_position_error", "final_newton_residual", "final_relative_newton_residual", "reference_energy_gradient", "line_search_failures", "substeps_rounding_floor", "reference_error_estimate", "reference_certified_threshold", "peak_memory", "memory_limit", "skipped_vertices", "avbd_kappa_max", "avbd_kappa_median", "ground_contacts"}},
          // The measure each run's stop test read and where it ended (harness/io/run_record.cpp).
          {"simulation", "string", {"convergence_measure"}},
          {"simulation", "float", {"final_convergence", "final_relative_convergence"}},
          {"linear", "string", {"system", "capture_solver", "direct_status"}},
          {"linear", "int", {"frame", "substep", "iteration", "nnz", "iterations"}},
          {"linear", "float", {"asymmetry", "rhs_norm", "direct_relative_residual", "final_relative_residual", "reported_relative_residual", "setup_time", "solve_time", "error_vs_direct", "error_vs_direct_l2"}},
      }),
      // Datasets: AMG level sizes, simulation runs' per-evaluation entries, linear runs' histories.
      expand({
          {"any", "float", {"level_rows", "level_nnz"}},
          {"simulation", "int", {"frame", "substep", "iteration", "linear_iterations", "linear_history/offset", "reference/iterations", "line_search_trials", "exact_hessian", "projected_elements", "active_bounds", "substep_success", "reference/success", "reference/certified"}},
          {"simulation", "float", {"dual_residual", "relative_dual_residual", "authors_dual_residual", "authors_relative_dual_residual", "primal_residual", "newton_residual", "relative_newton_residual", "energy", "wall_time", "step_time", "step_length", "fill_time", "linear_setup_time", "linear_solve_time", "linear_relative_residual", "linear_tolerance", "linear_history/residual", "linear_history/time", "position_error", "reference/relative_dual_residual", "reference/relative_energy_gradient", "final_positions", "distance_edges", "distance_rest_length", "inverted_tets", "relative_gradient_floor", "hessian_time", "reference/time", "reference/energy_gradient", "reference/gradient_floor", "reference/error_scale", "reference/error_estimate", "reference/contraction", "reference/certified_threshold"}},
          {"simulation", "string", {"linear_setup_action", "reference/status", "reference/source", "substep_status", "reference/certificate_note"}},
          // step = newton's inversions and the trust region's steps (harness/sim/trust_region.hpp).
          {"simulation", "int", {"inverted_elements", "trust_region_boundary", "trust_region_negative_curvature", "trust_region_rejections"}},
          {"simulation", "float", {"smallest_twist_sum", "trust_region_radius", "trust_region_ratio", "trust_region_shift", "trust_region_curvature"}},
          {"linear", "float", {"residual", "time", "solution"}},
      }),
  };
  return s;
}

namespace {
const SchemaName* find(const std::vector<SchemaName>& names, const std::string& name, const std::string& level) {
  for (const auto& n : names)
    if (n.name == name && (n.level == "any" || n.level == level)) return &n;
  return nullptr;
}
const char* type_name(SettingType t) {
  return t == SettingType::Int ? "int" : t == SettingType::Double ? "float" : "string";
}
bool type_fits(const std::string& type, int index) {  // index: 0 int, 1 float, 2 string
  if (type == "number") return index < 2;
  return (type == "int" && index == 0) || (type == "float" && index == 1) || (type == "string" && index == 2);
}
}  // namespace

void check_against_schema(const RunRecord& r) {
  const auto lv = r.attrs.find("level");
  const std::string level = lv == r.attrs.end() ? "" : attr_value_text(lv->second, 17);
  auto fail = [&](const std::string& what, const std::string& name) {
    throw std::logic_error("results schema: run '" + r.name + "' (level '" + level + "') holds the " + what + " '" + name +
                           "', which harness/io/schema.cpp does not list with that type (add it there and to results/README.md)");
  };
  for (const auto& [k, v] : r.attrs) {
    if (const ParamField* f = find_param(k)) {
      if (!type_fits(type_name(f->type), static_cast<int>(v.index()))) fail("parameter attribute", k);
      continue;
    }
    const SchemaName* n = find(results_schema().attributes, k, level);
    if (!n || !type_fits(n->type, static_cast<int>(v.index()))) fail("attribute", k);
  }
  for (const auto& [k, v] : r.datasets) {
    // DataValue: 0 float64, 1 int64, 2 string
    const int index = v.index() == 0 ? 1 : v.index() == 1 ? 0 : 2;
    const SchemaName* n = find(results_schema().datasets, k, level);
    if (!n || !type_fits(n->type, index)) fail("dataset", k);
  }
}

std::string schema_json() {
  auto list = [](const std::vector<SchemaName>& v) {
    std::ostringstream os;
    for (size_t i = 0; i < v.size(); ++i)
      os << (i ? ",\n" : "") << "    {\"name\": \"" << v[i].name << "\", \"level\": \"" << v[i].level << "\", \"type\": \""
         << v[i].type << "\"}";
    return os.str();
  };
  std::ostringstream os;
  os << "{\n  \"schema_version\": " << schema_version << ",\n  \"attributes\": [\n" << list(results_schema().attributes)
     << "\n  ],\n  \"datasets\": [\n" << list(results_schema().datasets) << "\n  ],\n  \"parameters\": [\n";
  const auto& fields = param_fields();
  for (size_t i = 0; i < fields.size(); ++i) {
    os << (i ? ",\n" : "") << "    {\"name\": \"" << fields[i].key << "\", \"type\": \"" << type_name(fields[i].type) << "\"}";
  }
  os << "\n  ]\n}\n";
  return os.str();
}

}  // namespace xb
