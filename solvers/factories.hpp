// Constructors of the linear solvers, used by the registry (solvers/registry.cpp).
#pragma once

#include "linear_solver.hpp"

namespace xb {
std::unique_ptr<LinearSolver> make_cg(const Params& p);
std::unique_ptr<LinearSolver> make_jacobi_pcg(const Params& p);
std::unique_ptr<LinearSolver> make_cholmod(const Params& p);
// The in-house MGPBD AMG-PCG (solvers/amg/mgpbd.cpp, solvers/amg/).
std::unique_ptr<LinearSolver> make_mgpbd(const Params& p);
// hypre and muelu run distributed under MPI (solvers/mpi/distributed.hpp).
std::unique_ptr<LinearSolver> make_hypre(const Params& p);
std::unique_ptr<LinearSolver> make_muelu(const Params& p);
}  // namespace xb
