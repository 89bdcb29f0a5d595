// MPI plumbing for the solvers that run distributed (hypre, muelu).
//
// Rank 0 runs the whole harness (scenes, assembly, the other solvers, results). A distributed
// solver on rank 0 is a DistributedSolver: it splits the rows of A into contiguous blocks, one
// per rank, broadcasts a command (create / setup / solve / destroy) and scatters the blocks;
// ranks > 0 sit in serve_workers() and run the same DistributedKernel code on their block.
// With one process nothing is sent: the kernel gets the whole matrix.
// Block systems (the primal form, SetupContext::block_size = 3): blocks are split at multiples of
// the block size, so a node's rows stay on one rank, and the block size and this rank's rows of
// the near-kernel basis travel with the setup command (RowBlock::block_size, ::near_kernel).
#pragma once

#include "../linear_solver.hpp"

#include <mpi.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace xb {

int mpi_rank();
int mpi_size();

// First row of each rank's block: offsets[r] .. offsets[r+1]-1 (offsets.size() = nranks + 1).
// Every offset is a multiple of block_size (n must be one too): nodes ⌊N·r/P⌋ … of N = n/block_size.
std::vector<long long> contiguous_rows(long long n, int nranks, int block_size = 1);

// Rows [first, first + rows()) of an n_global × n_global matrix, CSR with global column indices.
// A kernel takes the block size and the near-kernel from here, not from its SetupContext (whose
// near_kernel, on rank 0, has all n rows).
struct RowBlock {
  long long n_global = 0;
  long long first = 0;
  std::vector<int> rowptr{0};
  std::vector<long long> cols;
  std::vector<double> vals;
  int block_size = 1;          // unknowns per node, node-major; first and rows() are multiples
  Eigen::MatrixXd near_kernel;  // this block's rows of the n × k near-kernel basis (0 columns: none)
  int rows() const { return static_cast<int>(rowptr.size()) - 1; }
};

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

// Rank 0: a LinearSolver that drives the kernel `name` on all ranks.
std::unique_ptr<LinearSolver> make_distributed_solver(const std::string& name, const SolverSettings& p);

// Ranks > 0: serve rank 0's commands until it sends quit. Returns the exit code.
int serve_workers();
// Rank 0: release the workers (call once, before MPI_Finalize; no-op with one process).
void stop_workers();
// Every rank, before MPI_Finalize: finalize library runtimes that were started (Kokkos).
void finalize_external_libraries();

}  // namespace xb
