// The non-recursive V-cycle (Algorithm 2 of the supplemental) is Hierarchy::vcycle, declared in
// hierarchy.hpp; this header names it as a free function for the preconditioner.
#pragma once

#include "hierarchy.hpp"

namespace xb::amg {

// x = V(b): one V-cycle from a zero guess. x is resized.
inline void vcycle(Hierarchy& h, const Vector& b, Vector& x) { h.vcycle(b, x); }

}  // namespace xb::amg
