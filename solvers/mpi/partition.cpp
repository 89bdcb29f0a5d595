#include "partition.hpp"

#include "../../core/error.hpp"

#include <cstdlib>
#include <string>

namespace xb {

namespace {
// main() initialises MPI; library users without it (the unit tests) get it on first use,
// finalised at exit.
void ensure_mpi() {
  int init = 0;
  MPI_Initialized(&init);
  if (init) return;
  MPI_Init(nullptr, nullptr);
  std::atexit([] {
    int fin = 0;
    MPI_Finalized(&fin);
    if (fin) return;
    finalize_external_libraries();
    MPI_Finalize();
  });
}
}  // namespace

int mpi_rank() {
  ensure_mpi();
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int mpi_size() {
  ensure_mpi();
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

std::vector<long long> contiguous_rows(long long n, int nranks, int block_size) {
  if (block_size < 1 || n % block_size)
    throw Error(std::to_string(n) + " rows are not a whole number of blocks of " + std::to_string(block_size));
  const long long nodes = n / block_size;
  std::vector<long long> off(nranks + 1);
  for (int r = 0; r <= nranks; ++r) off[r] = block_size * (nodes * r / nranks);
  return off;
}

#ifdef XB_WITH_MUELU
void finalize_muelu_runtime();
#endif

void finalize_external_libraries() {
#ifdef XB_WITH_MUELU
  finalize_muelu_runtime();
#endif
}

}  // namespace xb
