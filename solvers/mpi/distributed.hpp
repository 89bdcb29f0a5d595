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

#include "distributed_kernel.hpp"
#include "partition.hpp"

#include <memory>
#include <string>

namespace xb {

// Rank 0: a LinearSolver that drives the kernel `name` on all ranks.
std::unique_ptr<LinearSolver> make_distributed_solver(const std::string& name, const SolverSettings& p);

// Ranks > 0: serve rank 0's commands until it sends quit. Returns the exit code.
int serve_workers();
// Rank 0: release the workers (call once, before MPI_Finalize; no-op with one process).
void stop_workers();

}  // namespace xb
