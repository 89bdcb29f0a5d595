// What a simulation run returns (harness/sim/simulation.hpp) and a results file records of it
// (harness/io/run_record.hpp; the schema is results/README.md): the status, the summary and the
// per-evaluation log. Plain data, so that the files below the simulation can read it.
#pragma once

#include <Eigen/Dense>

#include <map>
#include <string>
#include <vector>

namespace xb {

// Per outer iteration: one entry each time the dual residual is evaluated (iteration 0 is the
// predicted state, before any step). The linear_* entries describe the step that *led* to this
// state (zero at iteration 0 and for local methods).
struct IterationLog {
  std::vector<long long> frame, substep, iteration;
  std::vector<double> dual_residual;           // ‖C + α̃λ‖₂
  std::vector<double> relative_dual_residual;  // over the substep's iteration 0
  // The dual residual as the authors' code logs it (never the true one after iteration 0):
  //  - local methods (xpbd-*): ‖C(x̃) + α̃λ_k‖, C evaluated once, at the substep's predicted x̃;
  //  - global methods: ‖C(x_{k−1}) + α̃λ_k‖, C of the state before step k, λ after it.
  // Equal to dual_residual at iteration 0. The relative one is over that same iteration-0 value.
  std::vector<double> authors_dual_residual, authors_relative_dual_residual;
  std::vector<double> primal_residual;         // ‖g‖₂, g = M(x − x̃) − ∇Cᵀλ over free particles
  // Chen et al. 2023's Newton residual √(‖g‖² + ‖h‖²), h = C + α̃λ, and it over ‖Jᵀα̃⁻¹C(x̃)‖ = h²‖∇E(x̃)‖
  // (the same scale for every method; the Newton residual at x̃ where some α̃ = 0). Under step =
  // newton λ = −α̃⁻¹C, so h = 0 and newton_residual = h²‖∇E‖.
  std::vector<double> newton_residual, relative_newton_residual;
  std::vector<double> energy;                  // ‖x − x̃‖²_M/(2h²) + Σ C²/(2α) (α > 0)
  std::vector<double> wall_time;               // s since the substep began
  std::vector<double> step_time;               // s in the method step (assembly + setup + solve, or sweep)
  // Global methods: s filling the form's matrix (A = J M⁻¹Jᵀ + α̃ before the setup; K inside
  // linear_setup_time), so that a step splits into fill, setup or refresh, and solve.
  std::vector<double> fill_time;
  // Global methods: the step length of the step that led here (ω for step = fixed, the line
  // search's t for step = line_search); 0 at iteration 0 and for local methods.
  std::vector<double> step_length;
  // The line search's trials in the step that led here (step = line_search | newton; else 0), and
  // whether that step used the exact element Hessians (step = newton, xpbd.hessian_projection = adaptive).
  std::vector<long long> line_search_trials, exact_hessian;
  // Global methods: the elements whose Hessian that step projected (step = newton; geometric
  // stiffness full: those with a negative eigenvalue that the projection changed).
  std::vector<long long> projected_elements;
  // step = newton only, per entry: the rounding floor of ‖∇E‖ (harness/sim/newton.hpp) over its
  // value at x̃, the particles held on a plane (contact's active bounds), and the step's element
  // Hessians' time (outside fill_time, which is K's).
  std::vector<double> relative_gradient_floor;
  std::vector<long long> active_bounds;
  std::vector<double> hessian_time;  // s of that step filling the element Hessians (all its tries)
  // step = newton only, per entry: the tets with det F < 0 and the smallest σ₂ + σ₃ among them (the
  // ARAP energy's ridge is σ₂ + σ₃ = 0; +inf where no tet is inverted).
  std::vector<long long> inverted_elements;
  std::vector<double> smallest_twist_sum;
  // xpbd.globalization = trust_region only, of the step that led here (harness/sim/trust_region.hpp;
  // 0 at iteration 0): its radius, ρ, more_sorensen's σ, the smallest Rayleigh quotient of an element
  // mode in the exact K (< 0: K indefinite), whether it ended on the boundary or along negative
  // curvature, and the steps rejected before it.
  std::vector<double> trust_region_radius, trust_region_ratio, trust_region_shift, trust_region_curvature;
  std::vector<long long> trust_region_boundary, trust_region_negative_curvature, trust_region_rejections;
  std::vector<long long> linear_iterations;
  std::vector<double> linear_setup_time, linear_solve_time, linear_relative_residual;
  std::vector<double> linear_tolerance;  // the relative tolerance that step was given (linear.forcing)
  std::vector<std::string> linear_setup_action;
  // Residual histories of every linear solve, concatenated; solve k of entry i owns
  // [linear_history_offset[i], linear_history_offset[i+1]).
  std::vector<double> linear_history_residual, linear_history_time;
  std::vector<long long> linear_history_offset{0};
  // With RunOptions::reference only: per entry ‖x − x_ref‖_M over the substep's error scale (x_ref
  // from harness/sim/reference.hpp, recomputed every substep from the run's own x̃; the scale
  // ReferenceSolution::error_scale), and per substep what the reference reached and its
  // certificate (harness/sim/certificate.hpp).
  std::vector<double> position_error;
  std::vector<double> reference_relative_dual_residual;
  std::vector<double> reference_relative_energy_gradient;  // ‖∇E‖/‖∇E(x̃)‖ of the reference (every α̃ > 0)
  std::vector<long long> reference_iterations;
  std::vector<std::string> reference_status;
  std::vector<long long> reference_success;  // stop_reason_success of reference_status (1: a solution)
  std::vector<double> reference_energy_gradient, reference_gradient_floor;  // ‖∇E‖ (free) at x_ref, its floor; N
  std::vector<double> reference_error_scale;      // position_error's denominator
  std::vector<double> reference_error_estimate;   // the bound on ‖x_ref − x*‖_M over the scale (∞: none)
  std::vector<double> reference_contraction;      // q of that bound (NaN: no step)
  std::vector<long long> reference_certified;     // 1: positive definite on the free set and a bound
  std::vector<double> reference_certified_threshold;  // the finest threshold trusted (∞: none)
  std::vector<std::string> reference_certificate_note;  // why not certified ("" where it is)
  std::vector<double> reference_time;  // s of each substep's reference (off every clock)
  // Per substep, where its reference came from (RunOptions::reference_file): read (from the
  // file), stored (computed here and added to it) or computed (here; not stored: no file, or the
  // file holds one of another x̃ for that substep).
  std::vector<std::string> reference_source;
  // Per substep, how its outer loop ended: converged | max_iterations for XPBD's methods; under
  // step = newton the stop reason (harness/sim/stop_reason.hpp: converged, rounding_floor,
  // line_search_at_floor, max_iterations, line_search_failed), and the one success predicate's
  // value for it (stop_reason_success: 1 for converged or rounding_floor). A substep that ends
  // the run has none.
  std::vector<std::string> substep_status;
  std::vector<long long> substep_success;
};

struct RunResult {
  // ok | max_iterations | line_search_failed | reference_unconverged | diverged | nan | breakdown |
  // over_budget | out_of_memory | error (results/README.md)
  std::string status = "ok";
  std::string message;
  std::string form_used;      // dual | primal for global methods, none for local sweeps
  IterationLog log;
  long long outer_iterations = 0;   // method steps over all substeps
  double final_dual_residual = 0;   // of the last evaluation
  double relative_dual_residual = 0;
  double wall_time = 0;             // s, the whole run (without the reference's time)
  double reference_time = 0;        // s spent on references and errors (excluded from every clock)
  std::string reference_method;     // how the reference was computed ("" = no reference)
  std::string reference_file;       // the file of stored references ("" = none)
  int substeps_converged = 0, substeps_total = 0;
  std::map<std::string, double> stats;                     // solver statistics (+ run extras)
  std::map<std::string, std::vector<double>> arrays;       // per-level and similar arrays
  Eigen::Matrix3Xd final_positions;
};

}  // namespace xb
