// The module xpbd_bench._core: the C++ harness for the Python package (python/xpbd_bench/).
// MPI is initialised on import, as the CLI does in main (the distributed solvers need it), and
// finalised at interpreter exit.
#include "bindings.hpp"

#include "core/error.hpp"
#include "solvers/mpi/distributed.hpp"

#include <mpi.h>

namespace nb = nanobind;

namespace {
void finalize() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized) return;
  xb::stop_workers();
  xb::finalize_external_libraries();
  MPI_Finalize();
}
}  // namespace

NB_MODULE(_core, m) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  nb::module_::import_("atexit").attr("register")(nb::cpp_function(&finalize));
  nb::exception<xb::Error>(m, "Error", PyExc_ValueError);
  xb::py::bind_system(m);
  xb::py::bind_api(m);
  xb::py::bind_amg(m);
}
