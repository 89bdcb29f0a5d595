// The solver protocol (docs/python.md): a Python object with `name`, `setup(A, info)` and
// `solve(b, tol)` as a LinearSolver, so that it runs inside the stepper and `solve` like any
// built-in method, recorded as py:<name>. The GIL is taken only around the Python calls; the C++
// clock around each call includes the conversions and the interpreter's overhead.
#pragma once

#include "solvers/linear_solver.hpp"

#include <nanobind/nanobind.h>

#include <string>

namespace xb::py {

namespace nb = nanobind;

class PySolver final : public LinearSolver {
 public:
  // `solver` is borrowed (the GIL is taken here); tol: solve(b, tol)'s until set_tolerance.
  PySolver(nb::handle solver, double tol);
  ~PySolver() override;

  std::string name() const override { return "py:" + name_; }
  // Hands the object A as a scipy CSR view (valid until the next setup) and the info dict.
  void setup(const SparseMatrix& A, SetupKind kind, const SetupContext& ctx) override;
  // x from the object, checked (shape, finite); the residual is the harness's ‖b − Ax‖.
  LinearStats solve(const Vector& b, Vector& x) override;
  std::string last_setup_action() const override { return action_; }

 private:
  nb::object obj_;
  std::string name_;
  const SparseMatrix* A_ = nullptr;
  SparseMatrix compressed_;  // A's copy when it comes uncompressed (the view needs CSR arrays)
  double setup_time_ = 0;
  bool setup_pending_ = false;  // the next solve reports setup_time_
  std::string action_;
};

// The name a protocol object runs under: "py:" + its `name` (a str attribute or property).
std::string protocol_name(nb::handle solver);

}  // namespace xb::py
