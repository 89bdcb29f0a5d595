// The parts of the module _core (python/src/module.cpp), each bound in its own file.
#pragma once

#include <nanobind/nanobind.h>

namespace xb::py {
namespace nb = nanobind;
void bind_system(nb::module_& m);  // System, load_system (system.cpp)
void bind_api(nb::module_& m);     // command, scenes, solvers, parameters, read (api.cpp)
void bind_amg(nb::module_& m);     // AmgHierarchy (amg.cpp)
}  // namespace xb::py
