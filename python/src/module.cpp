// The module xpbd_bench._core: the C++ harness for the Python package (python/xpbd_bench/).
// MPI is initialised on import, as the CLI does in main (the distributed solvers need it), and
// finalised at interpreter exit.
#include "bindings.hpp"

#include "core/error.hpp"
#include "harness/io/atomic_file.hpp"
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
  // A failed write of an output (a full disk): xpbd_bench.WriteError, an Error and an OSError
  // with errno, strerror and filename; str() is the CLI's one line. Registered after Error, so
  // tried before it.
  nb::dict body;
  body["__module__"] = "xpbd_bench";
  body["__str__"] = nb::module_::import_("builtins").attr("BaseException").attr("__str__");  // the message, not "[Errno 28] ..."
  nb::object write_error = nb::module_::import_("builtins").attr("type")(
      "WriteError", nb::make_tuple(m.attr("Error"), nb::handle(PyExc_OSError)), body);
  m.attr("WriteError") = write_error;
  nb::register_exception_translator(
      [](const std::exception_ptr& p, void* type) {
        try {
          std::rethrow_exception(p);
        } catch (const xb::WriteError& e) {
          nb::object exc = nb::handle(static_cast<PyObject*>(type))(e.what());
          exc.attr("errno") = e.err;
          exc.attr("strerror") = nb::str(xb::errno_text(e.err).c_str());
          exc.attr("filename") = nb::str(e.path.c_str());
          PyErr_SetObject(static_cast<PyObject*>(type), exc.ptr());
        }
      },
      write_error.release().ptr());  // the module keeps it alive
  xb::py::bind_system(m);
  xb::py::bind_api(m);
  xb::py::bind_amg(m);
}
