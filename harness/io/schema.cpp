#include "schema.hpp"

#include "../params.hpp"

#include <sstream>
#include <stdexcept>

namespace xb {

const ResultsSchema& results_schema() {
  static const ResultsSchema s = {
      {
          // every run: what, how it ended, provenance
          {"level", "any", "string"}, {"scene", "any", "string"}, {"solver", "any", "string"},
          {"form_used", "any", "string"}, {"status", "any", "string"}, {"message", "any", "string"},
          {"git_sha", "any", "string"}, {"machine", "any", "string"}, {"created", "any", "string"},
          {"omp_threads", "any", "int"}, {"omp_wait_policy", "any", "string"}, {"load_average", "any", "float"},
          {"cpu_count", "any", "int"}, {"rows", "any", "number"},
          // solver statistics (statistics() of the LinearSolver)
          {"levels", "any", "float"}, {"operator_complexity", "any", "float"}, {"grid_complexity", "any", "float"},
          {"factor_nnz", "any", "float"}, {"factor_flops", "any", "float"}, {"mpi_ranks", "any", "float"},
          {"setup_count", "any", "float"}, {"refresh_count", "any", "float"}, {"setup_full", "any", "float"},
          {"setup_reused", "any", "float"}, {"setup_time_total", "any", "float"}, {"refresh_time_total", "any", "float"},
          {"primal_rows", "any", "float"}, {"primal_nonzeros", "any", "float"},
          // simulation runs
          {"profile", "simulation", "string"}, {"outer_iterations", "simulation", "int"},
          {"final_dual_residual", "simulation", "float"}, {"relative_dual_residual", "simulation", "float"},
          {"final_authors_dual_residual", "simulation", "float"}, {"wall_time", "simulation", "float"},
          {"substeps_total", "simulation", "int"}, {"substeps_converged", "simulation", "int"},
          {"nonzeros", "simulation", "float"}, {"particles", "simulation", "float"}, {"colors", "simulation", "float"},
          {"jacobi_relaxation_used", "simulation", "float"}, {"authors_skipped_last_sweep", "simulation", "float"},
          {"time_budget", "simulation", "float"}, {"reference", "simulation", "int"},
          {"reference_method", "simulation", "string"}, {"reference_dual_residual", "simulation", "float"},
          {"reference_substeps_unconverged", "simulation", "int"}, {"reference_time", "simulation", "float"},
          {"final_position_error", "simulation", "float"},
          {"sweep_spec", "simulation", "string"}, {"sweep_description", "simulation", "string"},
          {"sweep_params", "simulation", "string"}, {"sweep_point", "simulation", "string"},
          {"sweep_key", "simulation", "string"}, {"sweep_base", "simulation", "string"},
          {"sweep_index", "simulation", "int"}, {"sweep_repeat", "simulation", "int"},
          // linear runs (solve on a captured system)
          {"system", "linear", "string"}, {"frame", "linear", "int"}, {"substep", "linear", "int"},
          {"iteration", "linear", "int"}, {"capture_solver", "linear", "string"}, {"asymmetry", "linear", "float"},
          {"nnz", "linear", "int"}, {"rhs_norm", "linear", "float"}, {"direct_status", "linear", "string"},
          {"direct_relative_residual", "linear", "float"}, {"iterations", "linear", "int"},
          {"final_relative_residual", "linear", "float"}, {"reported_relative_residual", "linear", "float"},
          {"setup_time", "linear", "float"}, {"solve_time", "linear", "float"},
          {"error_vs_direct", "linear", "float"}, {"error_vs_direct_l2", "linear", "float"},
      },
      {
          {"level_rows", "any", "float"}, {"level_nnz", "any", "float"},
          // simulation runs: one entry per evaluation of the dual residual
          {"frame", "simulation", "int"}, {"substep", "simulation", "int"}, {"iteration", "simulation", "int"},
          {"dual_residual", "simulation", "float"}, {"relative_dual_residual", "simulation", "float"},
          {"authors_dual_residual", "simulation", "float"}, {"authors_relative_dual_residual", "simulation", "float"},
          {"primal_residual", "simulation", "float"}, {"energy", "simulation", "float"},
          {"wall_time", "simulation", "float"}, {"step_time", "simulation", "float"}, {"step_length", "simulation", "float"},
          {"linear_iterations", "simulation", "int"}, {"linear_setup_time", "simulation", "float"},
          {"linear_solve_time", "simulation", "float"}, {"linear_relative_residual", "simulation", "float"},
          {"linear_setup_action", "simulation", "string"}, {"linear_history/residual", "simulation", "float"},
          {"linear_history/time", "simulation", "float"}, {"linear_history/offset", "simulation", "int"},
          {"position_error", "simulation", "float"}, {"reference/relative_dual_residual", "simulation", "float"},
          {"reference/iterations", "simulation", "int"}, {"reference/status", "simulation", "string"},
          {"final_positions", "simulation", "float"}, {"distance_edges", "simulation", "float"},
          {"distance_rest_length", "simulation", "float"}, {"inverted_tets", "simulation", "float"},
          // linear runs
          {"residual", "linear", "float"}, {"time", "linear", "float"}, {"solution", "linear", "float"},
      },
  };
  return s;
}

namespace {
const SchemaName* find(const std::vector<SchemaName>& names, const std::string& name, const std::string& level) {
  for (const auto& n : names)
    if (n.name == name && (n.level == "any" || n.level == level)) return &n;
  return nullptr;
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
      const int want = f->type == SettingType::Int ? 0 : f->type == SettingType::Double ? 1 : 2;
      if (static_cast<int>(v.index()) != want) fail("parameter attribute", k);
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
    const char* type = fields[i].type == SettingType::Int ? "int" : fields[i].type == SettingType::Double ? "float" : "string";
    os << (i ? ",\n" : "") << "    {\"name\": \"" << fields[i].key << "\", \"type\": \"" << type << "\"}";
  }
  os << "\n  ]\n}\n";
  return os.str();
}

}  // namespace xb
