// The LinearSolver interface: every global method of the harness (cholmod, cg, jacobi-pcg,
// mgpbd, hypre, muelu) solves one SPD system through it — the dual A Δλ = b or the primal
// K Δx = f (harness/sim/simulation.cpp, harness/sim/primal_solve.hpp). Solvers see only a CSR
// matrix, its block size, an optional near-kernel basis and vectors.
#pragma once

#include "../core/sparse.hpp"

#include <Eigen/Dense>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace xb {

struct SolverSettings;

// What changed since the previous setup() call.
//  Structure: a new sparsity pattern (or the first call): analyse/coarsen from scratch.
//  Values:    same pattern, new values: a solver may reuse whatever depends only on the pattern
//             (CHOLMOD's analysis, AMG aggregates and P, ...). It must still be correct.
enum class SetupKind { Structure, Values };

// Context of a setup() call: where in a simulation it happens (lets a solver apply its lazy-setup
// policy; on the linear level frame = 0) and what is known about the matrix beyond its entries.
struct SetupContext {
  int frame = 0;
  int substep = 0;
  int iteration = 0;
  // Unknowns per node, stored node-major (rows b·i … b·i+b−1 belong to node i): 1 for the dual
  // system, 3 for the primal form (one particle's x, y, z).
  int block_size = 1;
  // n × k near-kernel basis (the primal form's 6 rigid-body modes at the current positions), or
  // null. Valid during setup() only: a solver that needs it later keeps a copy.
  const Eigen::MatrixXd* near_kernel = nullptr;
};

// The relative residual a solve is judged by, from the solver's residual vector r: by default
// ‖r‖₂/‖b‖₂. The primal form judges K's residual by the dual residual it implies,
// ‖J M⁻¹ r_K‖₂ / ‖b_dual‖₂, so both forms stop on one criterion.
using RelativeResidual = std::function<double(const Vector& r)>;

// z = P⁻¹r: a preconditioner's action (P symmetric positive definite for CG to be correct).
using Preconditioner = std::function<void(const Vector& r, Vector& z)>;

enum class LinearStatus {
  converged,       // ‖b − Ax‖₂ ≤ tol·‖b‖₂
  max_iterations,  // stopped at linear.max_iterations without reaching tol
  breakdown,       // the method broke down (not SPD, pᵀAp ≤ 0, singular factor, NaN)
};
const char* to_string(LinearStatus s);

// One solve's statistics. residual_history[k] is ‖r_k‖₂ (k = 0 is ‖b‖₂ for a zero start) and
// residual_time[k] the seconds since the start of solve() when it was known.
struct LinearStats {
  LinearStatus status = LinearStatus::converged;
  std::string message;  // why, for breakdown
  int iterations = 0;
  double setup_time = 0;  // seconds in the setup() call before this solve
  double solve_time = 0;  // seconds in solve()
  double final_relative_residual = 0;
  std::vector<double> residual_history;
  std::vector<double> residual_time;
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  virtual std::string name() const = 0;

  // A must stay alive and unchanged until the next setup() call (solvers may keep a pointer).
  virtual void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) = 0;

  // Solve A x = b from a zero initial guess to ‖r‖₂ ≤ tol·‖b‖₂ (tol = tolerance()).
  // x is resized by the solver. Returns the statistics of this solve; setup_time is that of
  // the setup() call that preceded it (0 if none did).
  virtual LinearStats solve(const Vector& b, Vector& x) = 0;

  // The relative tolerance of the following solves: linear.tol from the settings, until the
  // caller's forcing rule (linear.forcing, harness/sim/forcing.hpp) sets one per outer iteration.
  void set_tolerance(double tol) { tol_ = tol; }
  double tolerance() const { return tol_; }

  // Judge convergence (and the residual history) by `rel` instead of ‖r‖₂/‖b‖₂ from now on. Only
  // solvers whose Krylov loop is in-house can: they return true. The others return false and the
  // caller refines (solves again for the remaining residual) until `rel` is met.
  virtual bool set_relative_residual(RelativeResidual rel) {
    (void)rel;
    return false;
  }

  // The preconditioner of the last setup, z ≈ A⁻¹r with its P SPD where A is, for a Krylov loop
  // outside the solver (the trust region's Steihaug–Toint CG, harness/sim/newton_trust_region.cpp):
  // jacobi-pcg's inverse diagonal, mgpbd's V-cycle, exact cholmod's factor solve. Null where the
  // solver has none (cg: P = I) or its setup failed. Valid until the next setup().
  virtual Preconditioner preconditioner() { return nullptr; }

  // Scalar statistics of the current setup for the results (e.g. "levels",
  // "operator_complexity", "setup_kind_structure"). Keys are HDF5 attribute names.
  virtual std::map<std::string, double> statistics() const { return {}; }

  // Per-level or other array statistics (e.g. "level_rows"). Keys are dataset names.
  virtual std::map<std::string, std::vector<double>> array_statistics() const { return {}; }

  // What the last setup() actually did ("structure", "values", "reuse", ...), for the log.
  virtual std::string last_setup_action() const { return ""; }

 protected:
  explicit LinearSolver(double tol) : tol_(tol) {}

 private:
  double tol_;
};

// The registry of methods. A method is either a linear solver (global) or a local XPBD sweep.
struct MethodInfo {
  std::string name;
  bool local = false;      // xpbd-jacobi, xpbd-gs: no linear system
  bool available = true;   // false when the library was not built in
  std::string reason;      // why it is unavailable
  std::string description;
  bool distributed = false;  // hypre, muelu: runs on every MPI rank (solvers/mpi/)
  // vbd, avbd (local too): block descent on the incremental potential, its own outer loop
  // (harness/sim/block_descent.hpp), not an XPBD sweep.
  bool block_descent = false;
};
const std::vector<MethodInfo>& methods();  // the built-in ones
// A built-in or registered method, or null.
const MethodInfo* find_method(const std::string& name);

// Methods added at run time by a caller that builds its own solvers (the Python package's
// py:<name> solvers, python/): found by find_method and made by make_linear_solver like the
// built-in ones until unregistered, so every command runs them unchanged. Not listed by
// methods(). register_method throws xb::Error for a name already taken; both are thread-safe.
using SolverFactory = std::function<std::unique_ptr<LinearSolver>(const SolverSettings&)>;
void register_method(const MethodInfo& info, SolverFactory make);
void unregister_method(const std::string& name);

// Throws xb::Error for an unknown or unavailable name.
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const SolverSettings& p);

}  // namespace xb
