// Shared by the external-solver tests that start `mpirun` from inside a test process.
#pragma once

#include <string>
#include <unistd.h>

namespace xb::test {

inline const std::string mpirun = "mpirun -np 2 --oversubscribe --allow-run-as-root -x OMP_NUM_THREADS=1 ";

// This test process may itself be an MPI singleton (the solvers initialise MPI): the child
// mpirun must not inherit its Open MPI / PMIx environment. Returns an `env -u ...` prefix.
inline std::string clean_env() {
  std::string unset = "env";
  for (char** e = environ; *e; ++e) {
    const std::string kv = *e;
    const std::string k = kv.substr(0, kv.find('='));
    if (k.rfind("OMPI_", 0) == 0 || k.rfind("PMIX_", 0) == 0 || k.rfind("OPAL_", 0) == 0) unset += " -u " + k;
  }
  return unset + " ";
}

}  // namespace xb::test
