// The commands as the Python package calls them: the same functions as the CLI (one way to run,
// capture and solve), with the call's Python solvers registered as py:<name> methods while it runs
// and the GIL released for the whole command: several threads may run commands at once (libhdf5,
// not thread-safe here, is entered under one lock, harness/io/h5handle.hpp).
#include "bindings.hpp"
#include "convert.hpp"
#include "py_solver.hpp"

#include "core/error.hpp"
#include "harness/cli/commands.hpp"
#include "harness/io/recorder.hpp"
#include "harness/params.hpp"
#include "problems/scene.hpp"
#include "solvers/solver_settings.hpp"

#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <map>

namespace xb::py {

namespace {

// Each protocol object is a registered method py:<name> from construction to destruction. The
// factories keep borrowed handles: the caller's list holds the objects for the whole command.
class ScopedSolvers {
 public:
  explicit ScopedSolvers(const nb::list& solvers) {
    try {
      for (nb::handle obj : solvers) {
        const std::string name = protocol_name(obj);
        MethodInfo info{name, false, true, "", "a Python solver (the protocol of docs/python.md)"};
        register_method(info, [h = obj.ptr()](const SolverSettings& p) {
          return std::make_unique<PySolver>(nb::handle(h), p.linear.tol);
        });
        names_.push_back(name);
      }
    } catch (...) {
      release();  // no destructor runs for a half-built object
      throw;
    }
  }
  ~ScopedSolvers() { release(); }
  ScopedSolvers(const ScopedSolvers&) = delete;
  ScopedSolvers& operator=(const ScopedSolvers&) = delete;

 private:
  void release() {
    for (const auto& n : names_) unregister_method(n);
    names_.clear();
  }
  std::vector<std::string> names_;
};

const std::map<std::string, int (*)(const CommandArgs&)>& command_table() {
  static const std::map<std::string, int (*)(const CommandArgs&)> t = {
      {"run", cmd_run},       {"capture", cmd_capture}, {"solve", cmd_solve},
      {"report", cmd_report}, {"sweep", cmd_sweep},     {"pack", cmd_pack},
      {"repair", cmd_repair}};
  return t;
}

int command(const std::string& name, const std::vector<std::string>& args, const nb::list& solvers) {
  auto it = command_table().find(name);
  if (it == command_table().end()) throw Error("unknown command '" + name + "'");
  ScopedSolvers scope(solvers);
  int rc;
  {
    nb::gil_scoped_release release;
    rc = it->second(args);
  }
  if (PyErr_CheckSignals() != 0) throw nb::python_error();  // a Ctrl-C during the command
  return rc;
}

nb::list solver_list() {
  nb::list l;
  for (const auto& m : methods()) {
    nb::dict d;
    d["name"] = m.name;
    d["kind"] = m.local ? "local" : "global";
    d["available"] = m.available;
    d["reason"] = m.reason;
    d["description"] = m.description;
    l.append(d);
  }
  return l;
}

nb::list parameter_list() {
  nb::list l;
  const Params defaults;
  for (const auto& f : param_fields()) {
    nb::dict d;
    d["key"] = f.key;
    d["default"] = param_to_string(defaults, f);
    d["doc"] = f.doc;
    l.append(d);
  }
  return l;
}

nb::list read(const std::string& path) {
  std::vector<std::string> skipped;
  std::vector<RunRecord> runs;
  {
    nb::gil_scoped_release release;  // other threads go on while this one waits for a writer or reads
    runs = read_runs(path, true, &skipped);
  }
  for (const auto& s : skipped)
    if (PyErr_WarnEx(PyExc_RuntimeWarning, ("xpbd_bench.read: skipped: " + s).c_str(), 1) != 0) throw nb::python_error();
  nb::list l;
  for (const auto& r : runs) l.append(record_to_dict(r));
  return l;
}

nb::dict repair(const std::string& path) {
  RepairReport rep;
  {
    nb::gil_scoped_release release;
    rep = repair_results(path);
  }
  nb::dict d;
  d["runs"] = rep.runs;
  d["packed"] = rep.packed;
  d["relinked"] = rep.found.relinked;
  d["dangling"] = rep.found.dangling;
  d["removed"] = rep.found.removed;
  d["notes"] = rep.found.notes;
  return d;
}

}  // namespace

void bind_api(nb::module_& m) {
  m.def("command", &command, nb::arg("name"), nb::arg("args"), nb::arg("solvers"),
        "Runs an xpbd-bench command (run, capture, solve, report, sweep, pack, repair) with CLI arguments; the protocol objects "
        "in `solvers` are the methods py:<name> meanwhile. Returns the exit code; bad input raises xpbd_bench.Error.");
  m.def("protocol_name", &protocol_name, nb::arg("solver"),
        "py:<name> for an object of the solver protocol; raises Error naming what it lacks.");
  m.def("scenes", &scene_names, "The built-in scenes.");
  m.def("solvers", &solver_list, "The built-in methods: name, kind (local | global), available, reason, description.");
  m.def("parameters", &parameter_list, "Every parameter key: key, default, doc.");
  m.def("count_runs", &count_runs, nb::arg("path"),
        "The number of runs in a results file (0 if absent); raises Error for a file that is not one.");
  m.def("read", &read, nb::arg("path"), "Every run of a results file as a dict of its attributes and datasets.");
  m.def("repair", &repair, nb::arg("path"),
        "Rebuilds a results file's index from its run files (xpbd-bench repair): a dict of what it found.");
}

}  // namespace xb::py
