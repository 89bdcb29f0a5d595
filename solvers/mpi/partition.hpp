// The MPI world of the distributed solvers (distributed.hpp): the ranks, the rows each one owns
// and the row block it receives; MPI started on first use and finalised at exit.
#pragma once

#include <Eigen/Dense>
#include <mpi.h>

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

// Every rank, before MPI_Finalize: finalize library runtimes that were started (Kokkos).
void finalize_external_libraries();

}  // namespace xb
