#include "py_solver.hpp"

#include "convert.hpp"

#include "core/error.hpp"
#include "solvers/kernels.hpp"
#include "solvers/timer.hpp"

#include <nanobind/stl/string.h>

#include <cctype>

namespace xb::py {

std::string protocol_name(nb::handle solver) {
  nb::object n = nb::getattr(solver, "name", nb::none());
  if (!nb::isinstance<nb::str>(n) || nb::cast<std::string>(n).empty())
    throw Error("a Python solver needs a non-empty str attribute `name` (got " +
                nb::cast<std::string>(nb::repr(n)) + " on " + nb::cast<std::string>(nb::repr(solver)) + ")");
  const std::string name = nb::cast<std::string>(n);
  for (char c : name)  // it names runs (HDF5 groups) and goes through --solver's comma list
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.')
      throw Error("Python solver name '" + name + "': use letters, digits, '_', '-' and '.' only (it names runs)");
  for (const char* m : {"setup", "solve"})
    if (!nb::hasattr(solver, m) || !PyCallable_Check(solver.attr(m).ptr()))
      throw Error("Python solver '" + name + "' has no method " + m +
                  "() (the protocol: name, setup(A, info), solve(b, tol))");
  return "py:" + name;
}

PySolver::PySolver(nb::handle solver, double tol) : LinearSolver(tol) {
  nb::gil_scoped_acquire gil;
  obj_ = nb::borrow(solver);
  name_ = protocol_name(solver).substr(3);
}

PySolver::~PySolver() {
  nb::gil_scoped_acquire gil;  // the last reference may go here, outside the caller's GIL
  obj_.reset();
}

void PySolver::setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) {
  Timer t;
  if (A.isCompressed()) {
    A_ = &A;
  } else {
    compressed_ = A;
    compressed_.makeCompressed();
    A_ = &compressed_;
  }
  action_ = kind == SetupKind::Structure ? "setup" : "refresh";
  {
    nb::gil_scoped_acquire gil;
    try {
      nb::dict info;
      // The primal form is the one with a near-kernel (K's rigid modes, block size 3).
      info["form"] = ctx.near_kernel ? "primal" : "dual";
      info["block_size"] = ctx.block_size;
      info["near_kernel"] = ctx.near_kernel ? matrix_copy(*ctx.near_kernel) : nb::none();
      info["frame"] = ctx.frame;
      info["substep"] = ctx.substep;
      info["iteration"] = ctx.iteration;
      info["action"] = action_;
      obj_.attr("setup")(csr_view(*A_, nb::handle()), info);
    } catch (nb::python_error& e) {
      throw Error(name() + ": setup raised " + describe(e));
    }
  }
  setup_time_ = t.seconds();
  setup_pending_ = true;
}

LinearStats PySolver::solve(const Vector& b, Vector& x) {
  if (!A_) throw Error(name() + ": solve() before setup()");
  LinearStats st;
  Timer t;
  {
    nb::gil_scoped_acquire gil;
    try {
      nb::object res = obj_.attr("solve")(vector_view(b.data(), static_cast<size_t>(b.size()), nb::handle()), tolerance());
      nb::object xo = res;
      if (nb::isinstance<nb::tuple>(res) && nb::len(res) == 2) {  // (x, iterations)
        xo = res[0];
        nb::object its = res[1];
        if (!PyLong_Check(its.ptr()) || PyBool_Check(its.ptr()) || PyLong_AsLong(its.ptr()) < 0)
          throw Error(name() + ".solve returned (x, iterations) with iterations " + nb::cast<std::string>(nb::repr(its)) +
                      ", not an int >= 0");
        st.iterations = static_cast<int>(PyLong_AsLong(its.ptr()));
      } else {
        st.iterations = 1;  // one application of the method, as cholmod counts
      }
      x = to_vector(xo, A_->rows(), name() + ".solve");
    } catch (nb::python_error& e) {
      throw Error(name() + ": solve raised " + describe(e));
    }
  }
  st.solve_time = t.seconds();
  st.setup_time = setup_pending_ ? setup_time_ : 0;
  setup_pending_ = false;
  // The harness judges x itself: the residual of what came back, whatever the object thinks.
  Vector r;
  residual(*A_, x, b, r);
  const double bn = norm2(b), rn = norm2(r);
  st.final_relative_residual = bn > 0 ? rn / bn : rn;
  st.residual_history = {bn, rn};
  st.residual_time = {0, st.solve_time};
  st.status = st.final_relative_residual <= tolerance() ? LinearStatus::converged : LinearStatus::max_iterations;
  return st;
}

}  // namespace xb::py
