// The part of a distributed solver every rank runs on its row block (hypre, muelu), and where its
// kernels and their library options come from.
#pragma once

#include "../linear_solver.hpp"
#include "partition.hpp"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace xb {

// The part of a distributed solver that every rank runs on its row block. All calls are
// collective over MPI_COMM_WORLD. Statistics are only used on rank 0.
class DistributedKernel {
 public:
  virtual ~DistributedKernel() = default;
  // kind == Values: same pattern as the previous call, only A.vals differ.
  virtual void setup(const RowBlock& A, SetupKind kind, const SetupContext& ctx) = 0;
  // b and x are this rank's blocks (x is written). Zero initial guess, relative tolerance tol.
  // The returned residual_history is the global one (all ranks get the same numbers).
  virtual LinearStats solve(const std::vector<double>& b, std::vector<double>& x, double tol) = 0;

  // The hierarchy of the last setup: levels, complexities, setup counts, level sizes.
  std::map<std::string, double> statistics() const;
  std::map<std::string, std::vector<double>> array_statistics() const;
  std::string last_setup_action() const { return action_; }

 protected:
  // A setup that built a new hierarchy (full) or reused one; `action` is what is logged.
  void record_setup(const std::string& action, bool full);
  // Global rows and non-zeros per level (0 where this rank cannot see a level).
  void record_levels(std::vector<double> rows, std::vector<double> nnz);

 private:
  std::string action_;
  long long full_setups_ = 0, reused_setups_ = 0;
  std::vector<double> level_rows_, level_nnz_;
};

// Whether a method can run with more than one MPI process (hypre, muelu), and its kernel: both
// asked of the one registry (solvers/registry.cpp). The kernel throws xb::Error for a method
// without one in this build.
bool method_is_distributed(const std::string& name);
std::unique_ptr<DistributedKernel> make_distributed_kernel(const std::string& name, const SolverSettings& p);

// Kernel constructors (solvers/mpi/hypre.cpp, solvers/mpi/muelu.cpp), only when built in.
std::unique_ptr<DistributedKernel> make_hypre_kernel(const SolverSettings& p);
std::unique_ptr<DistributedKernel> make_muelu_kernel(const SolverSettings& p);

// The library options a SolverSettings maps to for a system with `block_size` unknowns per node (for
// tests and the README table): BoomerAMG's integer codes ("coarsen_type", "interp_type",
// "relax_type", "num_functions", "nodal", ...) and MueLu's parameter list as text.
std::map<std::string, double> hypre_options(const SolverSettings& p, int block_size = 1);
std::string muelu_parameter_text(const SolverSettings& p, int block_size = 1);

}  // namespace xb
